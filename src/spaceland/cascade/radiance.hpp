// What the 3D cascades store per probe and direction, how a lower ray merges with the probes above
// it, how a ray goes on to the sky, and how a surface reads a probe (seed 001 section 2.5, seed 000
// Alg. 9-11): the one copy every 3D radiance-cascade method uses.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "penumbra/image.hpp"
#include "penumbra/vec3.hpp"
#include "spaceland/cascade/levels.hpp"
#include "spaceland/cascade/store.hpp"
#include "spaceland/color.hpp"

namespace penumbra::spaceland::cascade {

// A direction that holds no radiance: into a probe's own surface, or a ray of an upper cascade
// that met a surface before its interval (what lies between its probe and its interval is not on
// the lower probes' rays, so it tells them nothing). Marked by a negative red (radiance is never
// negative) and left out wherever directions are averaged, so that the weights that remain sum to
// one (a uniform sky gives a L exactly at any map seam).
inline constexpr Rgb kNoLight{-1, 0, 0};
inline bool holds_light(const Rgb& c) {
  return c.r >= 0;
}

// What a ray picks up along one stretch of its interval.
struct Segment {
  Rgb radiance{};              // light reaching the segment's start from inside it
  Rgb transmittance{1, 1, 1};  // 0 once a surface is met
  float t_end = 0;             // where it stopped: its end, or where it met a surface
  bool blocked = false;        // a surface ended it
};

// What a ray sees along a segment and, where the segment does not end on a surface, `beyond` it
// through the segment's transmittance.
inline Rgb then(const Segment& s, Rgb beyond) {
  return s.blocked ? s.radiance : s.radiance + s.transmittance * beyond;
}

// A ray that no upper ray continues (no probe above has light its way) goes on by itself from
// `from` to infinity, then sees the sky; `reach`, where given, becomes where it stopped if a
// surface stopped it (the spread sphere lights are seen through it). A tracer has
// trace(origin, dir, t0, t1) -> Segment and sky(dir) -> Rgb (the methods' own: Embree rays, the
// voxel march).
template <class Tracer>
Rgb continue_to_sky(Tracer& tracer, Vec3 origin, Vec3 dir, float from, float* reach = nullptr) {
  const Segment rest = tracer.trace(origin, dir, from, kInfinity);
  if (reach && rest.blocked) *reach = rest.t_end;
  return then(rest, tracer.sky(dir));
}

// The probes of the cascade above that a point reads and their weights (4 on the screen, 8 in a
// grid, 8 with the min-max merge's two per tile). The layout fills it; zero weights take no part.
struct Corners {
  std::array<std::uint64_t, 8> index{};
  std::array<float, 8> w{};
  int n = 0;
};

// The radiance upper probe q sends towards lower direction (u, v): the mean of its split x split
// children (the upper map's cells inside the lower one) that hold light and that keep(q, cell)
// accepts (cell: the child's index in the upper map; the surface cascades keep those on the lower
// ray's side of the surface), the bilinear sample of the upper map at the lower cell's centre,
// which crosses no seam (4x4: their box mean); false when none counts.
template <class Keep>
inline bool children_mean(const RadianceStore& upper, std::uint64_t q, int u, int v, int split,
                          Rgb& mean, Keep&& keep) {
  const Rgb* probe = upper.probe(q);
  const std::size_t side = std::size_t(upper.side());
  Rgb sum{};
  int n = 0;
  for (int dv = 0; dv < split; ++dv)
    for (int du = 0; du < split; ++du) {
      const std::size_t cell = std::size_t(split * v + dv) * side + std::size_t(split * u + du);
      const Rgb& c = probe[cell];
      if (!holds_light(c) || !keep(q, cell)) continue;
      sum += c;
      ++n;
    }
  if (n == 0) return false;
  mean = sum * (1.0f / float(n));
  return true;
}
inline bool children_mean(const RadianceStore& upper, std::uint64_t q, int u, int v, int split,
                          Rgb& mean) {
  return children_mean(upper, q, u, v, split, mean,
                       [](std::uint64_t, std::size_t) { return true; });
}

// Merging a lower ray with the cascade above (seed 001 eq. 13-14): the upper probes around it,
// each through children_mean, weighted and normalised over those that have light this way; false
// where none does (the ray then goes on by itself: continue_to_sky).
template <class Keep>
inline bool merge_children(const RadianceStore& upper, const Corners& c, int u, int v, int split,
                           Rgb& merged, Keep&& keep) {
  Rgb sum{}, got;
  float weight = 0;
  for (int j = 0; j < c.n; ++j) {
    const float w = c.w[std::size_t(j)];
    if (w > 0 && children_mean(upper, c.index[std::size_t(j)], u, v, split, got, keep)) {
      sum += got * w;
      weight += w;
    }
  }
  if (!(weight > 0)) return false;
  merged = sum * (1 / weight);
  return true;
}
inline bool merge_children(const RadianceStore& upper, const Corners& c, int u, int v, int split,
                           Rgb& merged) {
  return merge_children(upper, c, u, v, split, merged,
                        [](std::uint64_t, std::size_t) { return true; });
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

// The same over a probe of a store.
inline bool cosine_mean(const std::vector<Vec3>& dirs, Vec3 n, const RadianceStore& store,
                        std::uint64_t q, Rgb& out) {
  const Rgb* probe = store.probe(q);
  return cosine_mean(
      dirs, n, [&](std::size_t d) -> const Rgb& { return probe[d]; }, out);
}

// The mean of the values that hold light among `values` (pre-averaged sub-probes); kNoLight where
// none does.
template <class Values>
Rgb mean_with_light(const Values& values) {
  Rgb sum{};
  int n = 0;
  for (const Rgb& got : values) {
    if (!holds_light(got)) continue;
    sum += got;
    ++n;
  }
  return n > 0 ? sum * (1.0f / float(n)) : kNoLight;
}

// Cascades from the top down (seed 000 Alg. 9): solve(i, upper, lower) fills cascade i's store
// from the one above (empty for the top), which it then replaces. Returns cascade 0's store.
template <class SolveCascade>
RadianceStore top_down(const Levels& levels, SolveCascade&& solve) {
  RadianceStore upper, lower;
  for (int i = levels.count - 1; i >= 0; --i) {
    solve(i, static_cast<const RadianceStore&>(upper), lower);
    std::swap(upper, lower);
  }
  return upper;
}

}  // namespace penumbra::spaceland::cascade
