// Rays, hits and the offsets that start a ray off a surface: plain data that cameras, lights,
// media and methods share, apart from any accelerator (the Embree wrapper includes this, not the
// other way round).
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "penumbra/vec3.hpp"

namespace penumbra::spaceland {

struct Ray {
  Vec3 origin;
  Vec3 direction;  // need not be unit; t is in units of its length
  float tmin = 0;
  float tmax = 3.0e38f;
};

// What a closest-hit query found.
enum class ShapeKind : std::uint8_t { triangle, sphere, disk };

struct Hit {
  float t = 0;
  Vec3 position;          // on the surface (origin + t direction, refined for analytic shapes)
  Vec3 geometric_normal;  // unit, as the surface is oriented (not yet turned to the ray)
  Vec3 shading_normal;    // unit: interpolated vertex normal where the mesh has them
  float u = 0, v = 0;     // texture coordinates (0 where the mesh has none)
  float b1 = 0, b2 = 0;   // a triangle's barycentrics of its vertices 1 and 2
  std::uint32_t material = 0;
  int object = -1;
  ShapeKind kind = ShapeKind::triangle;
  std::uint32_t shape = 0;      // mesh, sphere or disk index in the Scene
  std::uint32_t primitive = 0;  // triangle index within the mesh
};

// Wächter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection" (Ray Tracing
// Gems, ch. 6): where a ray leaving a surface at `p` with geometric normal `n` towards `direction`
// starts: 256 ulps of each coordinate along the normal, to the side `direction` goes. A coordinate
// near zero has ulps too small to cover the hit's rounding error, which is that of the point's
// largest coordinate m: there the offset is 16 ulps of m (m 2^-19), or of `scale` (the scene's
// largest coordinate) at the origin. It is not a fraction of the scene's scale: a ground disk 1000
// across would lift every point of y = 0 by 0.015 and bias light from objects a unit away
// (docs/QUALITY.md, the sky over a plane).
inline Vec3 spawn_point(Vec3 p, Vec3 n, Vec3 direction, float scale) {
  if (dot(n, direction) < 0) n = -n;
  const float m = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  const float near_zero = m / 32;
  const float floor_offset = (m > 0 ? m : scale) * 0x1.0p-19f;
  Vec3 r;
  for (int i = 0; i < 3; ++i) {
    const auto ulps = std::int32_t(256 * n[i]);
    if (std::abs(p[i]) <= near_zero)
      r[i] = p[i] + floor_offset * n[i];
    else
      r[i] = std::bit_cast<float>(std::bit_cast<std::int32_t>(p[i]) + (p[i] < 0 ? -ulps : ulps));
  }
  return r;
}

// An upper bound of spawn_point's offset in a scene of that scale: 256 ulps of a coordinate are
// at most 2^-15 of it.
inline float spawn_epsilon(float scale) {
  return scale / 32768;
}

}  // namespace penumbra::spaceland
