// Affine transforms of points, directions and normals: the format's object transforms and glTF's
// node matrices.
#pragma once

#include <array>
#include <cmath>
#include <numbers>

#include "penumbra/vec3.hpp"

namespace penumbra::spaceland {

// x' = M x + t, M row-major. Composed and inverted in double so that chains of nodes do not
// lose precision.
struct Affine {
  std::array<double, 9> m{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::array<double, 3> t{0, 0, 0};

  static Affine scale(double sx, double sy, double sz) {
    Affine a;
    a.m = {sx, 0, 0, 0, sy, 0, 0, 0, sz};
    return a;
  }
  static Affine translate(double x, double y, double z) {
    Affine a;
    a.t = {x, y, z};
    return a;
  }
  // About one axis (0 x, 1 y, 2 z), counter-clockwise looking down the axis, in degrees.
  static Affine rotate(int axis, double degrees) {
    const double r = degrees * std::numbers::pi / 180, c = std::cos(r), s = std::sin(r);
    Affine a;
    if (axis == 0) a.m = {1, 0, 0, 0, c, -s, 0, s, c};
    if (axis == 1) a.m = {c, 0, s, 0, 1, 0, -s, 0, c};
    if (axis == 2) a.m = {c, -s, 0, s, c, 0, 0, 0, 1};
    return a;
  }
  // The format's transform: scale, then rotate about x, y, z, then translate.
  static Affine trs(Vec3 scale, Vec3 rotate_degrees, Vec3 translation) {
    return Affine::translate(translation.x, translation.y, translation.z) *
           Affine::rotate(2, rotate_degrees.z) * Affine::rotate(1, rotate_degrees.y) *
           Affine::rotate(0, rotate_degrees.x) * Affine::scale(scale.x, scale.y, scale.z);
  }

  // this after b: (this * b)(x) = this(b(x)).
  Affine operator*(const Affine& b) const {
    Affine r;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        r.m[i * 3 + j] = m[i * 3 + 0] * b.m[0 * 3 + j] + m[i * 3 + 1] * b.m[1 * 3 + j] +
                         m[i * 3 + 2] * b.m[2 * 3 + j];
      r.t[i] = m[i * 3 + 0] * b.t[0] + m[i * 3 + 1] * b.t[1] + m[i * 3 + 2] * b.t[2] + t[i];
    }
    return r;
  }

  double determinant() const {
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
           m[2] * (m[3] * m[7] - m[4] * m[6]);
  }

  Vec3 point(Vec3 p) const {
    return {float(m[0] * p.x + m[1] * p.y + m[2] * p.z + t[0]),
            float(m[3] * p.x + m[4] * p.y + m[5] * p.z + t[1]),
            float(m[6] * p.x + m[7] * p.y + m[8] * p.z + t[2])};
  }
  Vec3 direction(Vec3 d) const {
    return {float(m[0] * d.x + m[1] * d.y + m[2] * d.z),
            float(m[3] * d.x + m[4] * d.y + m[5] * d.z),
            float(m[6] * d.x + m[7] * d.y + m[8] * d.z)};
  }
  // Normals go through the inverse transpose (the cofactor matrix, up to a positive factor when
  // the determinant is positive); the result is normalised. A mirroring transform flips them,
  // which is harmless: surfaces are two-sided.
  Vec3 normal(Vec3 n) const {
    const double c[9] = {
        m[4] * m[8] - m[5] * m[7], m[5] * m[6] - m[3] * m[8], m[3] * m[7] - m[4] * m[6],
        m[2] * m[7] - m[1] * m[8], m[0] * m[8] - m[2] * m[6], m[1] * m[6] - m[0] * m[7],
        m[1] * m[5] - m[2] * m[4], m[2] * m[3] - m[0] * m[5], m[0] * m[4] - m[1] * m[3]};
    // c is the cofactor matrix, row-major: n' = c n (c^T n would be the inverse's turn).
    const double x = c[0] * n.x + c[1] * n.y + c[2] * n.z;
    const double y = c[3] * n.x + c[4] * n.y + c[5] * n.z;
    const double z = c[6] * n.x + c[7] * n.y + c[8] * n.z;
    const double len = std::sqrt(x * x + y * y + z * z);
    if (!(len > 0)) return n;
    return {float(x / len), float(y / len), float(z / len)};
  }
};

}  // namespace penumbra::spaceland
