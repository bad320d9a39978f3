// The equal-area octahedral map (Clarberg 2008, "Fast Equal-Area Mapping of the (Hemi)Sphere
// using SIMD"): unit directions <-> the square [-1, 1]^2, the octahedron's faces unfolded so that
// the lower hemisphere fills the corners. Equal cells of the square hold equal solid angles, so a
// d x d map's cells each cover 4 pi / d^2 steradians and a sum over them needs no cell weights.
// The map's pole is the z axis.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "penumbra/vec3.hpp"

namespace penumbra::octahedral {

namespace detail {

// atan2(y, x) for y, x >= 0, not both 0, within 1e-8 (measured over 10^7 pairs; the map keeps
// floats): Cephes' atanf polynomial after its range reduction, cheaper than libm's atan2, which the
// cascades' sphere lights called a few times per light a probe claims (a tenth of the time).
inline double quarter_atan2(double y, double x) {
  const bool swap = y > x;  // atan2(y, x) = pi/2 - atan2(x, y)
  double t = swap ? x / y : y / x, base = 0;
  if (t > 0.41421356237309503) {  // tan(pi/8): atan t = pi/4 + atan((t - 1) / (t + 1))
    base = std::numbers::pi / 4;
    t = (t - 1) / (t + 1);
  }
  const double z = t * t;
  const double a =
      base +
      (((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z - 3.33329491539e-1) *
          z * t +
      t;
  return swap ? std::numbers::pi / 2 - a : a;
}

}  // namespace detail

// Unit direction d -> (u, v) in [-1, 1]^2.
inline std::array<float, 2> encode(Vec3 d) {
  const double ax = std::abs(d.x), ay = std::abs(d.y), az = std::abs(d.z);
  const double r = std::sqrt(std::max(0.0, 1 - az));
  const double phi = (ax == 0 && ay == 0) ? 0.0 : detail::quarter_atan2(ay, ax);  // [0, pi/2]
  double v = phi * (2 / std::numbers::pi) * r;
  double u = r - v;
  if (d.z < 0) {  // the lower hemisphere folds out to the corners
    const double t = u;
    u = 1 - v;
    v = 1 - t;
  }
  return {float(std::copysign(u, double(d.x))), float(std::copysign(v, double(d.y)))};
}

// (u, v) in [-1, 1]^2 -> unit direction.
inline Vec3 decode(double u, double v) {
  const double au = std::abs(u), av = std::abs(v);
  const double sd = 1 - (au + av);
  const double r = 1 - std::abs(sd);
  const double phi = (r == 0 ? 1 : (av - au) / r + 1) * (std::numbers::pi / 4);
  const double z = std::copysign(1 - r * r, sd);
  const double s = r * std::sqrt(std::max(0.0, 2 - r * r));
  const double x = std::copysign(std::cos(phi) * s, u), y = std::copysign(std::sin(phi) * s, v);
  const double len = std::sqrt(x * x + y * y + z * z);
  return {float(x / len), float(y / len), float(z / len)};
}

// The direction at the centre of cell (i, j) of a side x side map (i along u, j along v).
inline Vec3 cell_direction(int i, int j, int side) {
  return decode(2 * (i + 0.5) / side - 1, 2 * (j + 0.5) / side - 1);
}

// The cell of a side x side map that holds direction d.
inline std::array<int, 2> cell_of(Vec3 d, int side) {
  const std::array<float, 2> uv = encode(d);
  const int i = std::clamp(int((uv[0] + 1) * 0.5f * side), 0, side - 1);
  const int j = std::clamp(int((uv[1] + 1) * 0.5f * side), 0, side - 1);
  return {i, j};
}

// Every cell's centre direction of a side x side map, row by row (index j * side + i).
inline std::vector<Vec3> map_directions(int side) {
  std::vector<Vec3> dirs(std::size_t(side) * side);
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) dirs[std::size_t(j) * side + i] = cell_direction(i, j, side);
  return dirs;
}

}  // namespace penumbra::octahedral
