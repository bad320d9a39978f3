// What the 3D cascades (SPWI's screen-space probes and the world-space probe grid) store per
// probe and direction, and how a surface reads it.
#pragma once

#include <cstddef>
#include <vector>

#include "penumbra/image.hpp"
#include "penumbra/vec3.hpp"
#include "spaceland/color.hpp"

namespace penumbra::spaceland {

// A direction that holds no radiance: into a probe's own surface, or a ray of an upper cascade
// that met a surface before its interval (what lies between its probe and its interval is not on
// the lower probes' rays, so it tells them nothing). Marked by a negative red (radiance is never
// negative) and left out wherever directions are averaged, so that the weights that remain sum to
// one (a uniform sky gives a L exactly at any map seam).
inline constexpr Rgb kNoLight{-1, 0, 0};
inline bool holds_light(const Rgb& c) {
  return c.r >= 0;
}

// A probe's cosine-weighted mean radiance over the hemisphere of unit normal n (irradiance / pi),
// over the directions `dirs` of an equal-area map whose radiance `at(d)` gives, those without
// light left out; false where none with light faces n.
template <class At>
bool cosine_mean(const std::vector<Vec3>& dirs, Vec3 n, At&& at, Rgb& out) {
  Rgb sum{};
  float weight = 0;
  for (std::size_t d = 0; d < dirs.size(); ++d) {
    const float cos_t = dot(n, dirs[d]);
    if (cos_t <= 0) continue;
    const Rgb& r = at(d);
    if (!holds_light(r)) continue;
    sum += r * cos_t;
    weight += cos_t;
  }
  if (!(weight > 0)) return false;
  out = sum * (1 / weight);
  return true;
}

}  // namespace penumbra::spaceland
