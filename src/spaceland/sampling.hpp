// Directions drawn from two uniform numbers, written once for every 3D method: cosine-weighted
// about a normal, uniform on the sphere, uniform in a cone.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "core/math.hpp"
#include "penumbra/vec3.hpp"

namespace penumbra::spaceland {

// Cosine-weighted about the unit normal n (density cos / pi).
inline Vec3 cosine_direction(Vec3 n, std::array<float, 2> u) {
  const double r = std::sqrt(double(u[0])), phi = kTwoPi * u[1];
  const double z = std::sqrt(std::max(0.0, 1 - double(u[0])));
  Vec3 t, b;
  orthonormal_basis(n, t, b);
  return normalize(t * float(r * std::cos(phi)) + b * float(r * std::sin(phi)) + n * float(z));
}

// Uniform on the unit sphere (density 1 / 4 pi).
inline Vec3 uniform_sphere(std::array<float, 2> u) {
  const double z = 1 - 2 * double(u[0]), r = std::sqrt(std::max(0.0, 1 - z * z));
  const double phi = kTwoPi * u[1];
  return {float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)};
}

// Uniform in the cone around the unit `axis` (t, b: a basis around it) whose half-angle has
// 1 - cos = `width`, given so that small cones keep their precision (density 1 / (2 pi width)).
inline Vec3 cone_direction(Vec3 axis, Vec3 t, Vec3 b, double width, std::array<float, 2> u) {
  const double one_minus_cos = u[0] * width;
  const double cos_t = 1 - one_minus_cos;
  const double sin_t = std::sqrt(std::max(0.0, one_minus_cos * (2 - one_minus_cos)));
  const double phi = kTwoPi * u[1];
  return normalize(axis * float(cos_t) + t * float(sin_t * std::cos(phi)) +
                   b * float(sin_t * std::sin(phi)));
}

}  // namespace penumbra::spaceland
