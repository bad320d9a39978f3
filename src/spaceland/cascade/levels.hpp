// The 3D cascade hierarchy's laws (seed 001 section 2.5): where each cascade's probes sit apart,
// how many directions they hold and which interval they trace. One definition for every 3D
// method; a method picks the growth rates (SPWI: branching 4 or 16 on the screen, the grid: 2x
// spacing, 4x directions, 2x intervals in world space) and the first cascade's values.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "core/octahedral.hpp"
#include "penumbra/vec3.hpp"

namespace penumbra::spaceland::cascade {

// The most cascades any 3D method plans: past it the top's map would pass 2^12 a side.
inline constexpr int kMaxCascades = 12;
inline constexpr float kInfinity = std::numeric_limits<float>::infinity();

// Cascade i: probes spacing0 2^(spacing_step i) apart, a (side0 2^(side_step i))^2 octahedral
// map of directions, and the interval [0, t0] (i = 0) or [t0 g^(i-1), t0 g^i] above, with
// g = 2^interval_step. The top cascade's interval runs on to infinity: its misses see the sky.
struct Levels {
  int count = 0;
  int spacing0 = 1, side0 = 1;
  int spacing_step = 1, side_step = 1, interval_step = 1;  // log2 of each growth per cascade
  float t0 = 0;                                            // world units

  int spacing(int i) const { return spacing0 << (spacing_step * i); }
  int side(int i) const { return side0 << (side_step * i); }
  std::size_t directions(int i) const { return std::size_t(side(i)) * std::size_t(side(i)); }
  // Children of a direction along each side of the map above: 2 (4 children), 4 (16).
  int split() const { return 1 << side_step; }
  bool top(int i) const { return i == count - 1; }
  float interval_start(int i) const {
    return i == 0 ? 0.0f : t0 * float(1u << (interval_step * (i - 1)));
  }
  // Where the interval ends by the law alone (what the cascade count is derived from).
  float nominal_end(int i) const { return t0 * float(1u << (interval_step * i)); }
  // Where it ends as traced: the top one to infinity.
  float interval_end(int i) const { return top(i) ? kInfinity : nominal_end(i); }
};

// The fewest cascades n (1 <= n <= most) for which `short_of(n - 1)` no longer holds: the one
// derivation of a cascade count (an interval short of the scene's reach, a probe spacing short
// of the screen's diagonal).
template <class ShortOf>
int count_until(int most, ShortOf&& short_of) {
  int n = 1;
  while (n < most && short_of(n - 1)) ++n;
  return n;
}

// Enough cascades that the last nominal interval reaches `reach`, at most `most`.
inline int count_to_reach(const Levels& l, double reach, int most) {
  return count_until(most, [&](int i) { return double(l.nominal_end(i)) < reach; });
}

// The frame a probe's direction maps lie in: world directions into the map's frame and back. The
// world's axes for SPWI and the grid; a chart's own for surface cascades (atlas::direction_frame).
struct MapFrame {
  Vec3 x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
  Vec3 to_world(Vec3 l) const { return x * l.x + y * l.y + z * l.z; }
  Vec3 to_local(Vec3 d) const { return {dot(d, x), dot(d, y), dot(d, z)}; }
};

// The directions of cascade i: the centres of its equal-area octahedral map's cells, row by row
// (index v * side + u).
inline std::vector<Vec3> direction_map(const Levels& l, int i) {
  return octahedral::map_directions(l.side(i));
}

}  // namespace penumbra::spaceland::cascade
