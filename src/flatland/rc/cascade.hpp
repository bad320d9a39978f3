// Geometry of flatland radiance cascades: probe grids, ray directions and intervals. Each of
// these is defined here once and used by every kernel.
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.hpp"
#include "penumbra/flatland/render.hpp"

namespace penumbra::flatland::rc {

// Cascade n: probes every s0 * 2^n cells, Q0 * b^n directions, interval [t_n, t_{n+1}].
struct Cascade {
  int n = 0;
  int spacing = 1;  // cells between probes
  int probes_x = 0, probes_y = 0;
  int directions = 0;
  float t_begin = 0, t_end = 0;     // the radiance interval, distance from the probe in cells
  std::vector<float> dir_x, dir_y;  // unit direction of ray k

  std::size_t size() const { return std::size_t(directions) * probes_x * probes_y; }
  // Direction-first layout: all probes of direction k are contiguous, row by row.
  std::size_t index(int k, int px, int py) const {
    return (std::size_t(k) * probes_y + py) * probes_x + px;
  }
  float probe_x(int i) const { return (float(i) + 0.5f) * float(spacing); }
  float probe_y(int j) const { return (float(j) + 0.5f) * float(spacing); }
};

// Direction of ray k of a probe with `count` rays: angle 2pi (k + 1/2) / count from +x
// towards +y. Ray k of cascade n covers the angles of rays b*k .. b*k+b-1 of cascade n+1.
void ray_direction(int k, int count, float& dx, float& dy);

// Interval of cascade n: [0, t0] for n = 0, then [t0 b^(n-1), t0 b^n]; lengths grow by the
// branching factor, so the last cascade of a hierarchy reaches t0 b^(N-1).
void cascade_interval(int n, float t0, int branching, float& t_begin, float& t_end);

// Enough cascades that the last interval ends beyond the grid diagonal.
int cascade_count(int width, int height, float t0, int branching);

// Directions of a cascade-n probe, Q0 * b^n, saturating far above any usable count.
std::int64_t top_directions(int q0, int branching, int n);

// Largest number of directions a probe may have (the top cascade's direction tables and the
// merges index directions with int).
inline constexpr std::int64_t kMaxDirections = std::int64_t(1) << 24;

// The whole hierarchy for a grid (options.cascades == 0 derives the count): sizes only, so it
// can be planned and its memory estimated before anything large is allocated.
std::vector<Cascade> plan_cascades(int width, int height, const RcOptions& options);

// Fills every cascade's direction tables (after the memory check).
void fill_directions(std::vector<Cascade>& plan);

// Bytes of cascade storage the method keeps alive at once.
std::uint64_t cascade_bytes(const std::vector<Cascade>& plan, const RcOptions& options);

}  // namespace penumbra::flatland::rc
