// A 3-vector in double, for the few computations whose float rounding matters: hits refined from
// Embree's (ray_scene.cpp) and the camera's basis from vectors that may be 1e-30 long.
#pragma once

#include <cmath>

#include "penumbra/vec3.hpp"

namespace penumbra {

struct D3 {
  double x, y, z;
};
inline D3 d3(Vec3 a) {
  return {a.x, a.y, a.z};
}
inline Vec3 f3(D3 a) {
  return {float(a.x), float(a.y), float(a.z)};
}
inline D3 operator-(D3 a, D3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline D3 operator+(D3 a, D3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline D3 operator*(double s, D3 a) {
  return {s * a.x, s * a.y, s * a.z};
}
inline double dot(D3 a, D3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline D3 cross(D3 a, D3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
// The unit vector of a non-zero `v`, scaled by its largest component first so that a tiny
// vector does not underflow when squared.
inline D3 normalize_scaled(D3 v) {
  const double m = std::fmax(std::fabs(v.x), std::fmax(std::fabs(v.y), std::fabs(v.z)));
  v = {v.x / m, v.y / m, v.z / m};  // dividing: 1 / m overflows for a denormal m
  const double len = std::sqrt(dot(v, v));
  return {v.x / len, v.y / len, v.z / len};
}

}  // namespace penumbra
