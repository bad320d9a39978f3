#include "flatland/rc/cascade.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "flatland/interval.hpp"

namespace penumbra::flatland::rc {

void ray_direction(int k, int count, float& dx, float& dy) {
  const double angle = kTwoPi * (double(k) + 0.5) / double(count);
  dx = float(std::cos(angle));
  dy = float(std::sin(angle));
}

void cascade_interval(int n, float t0, int branching, float& t_begin, float& t_end) {
  t_begin = n == 0 ? 0.0f : float(double(t0) * std::pow(double(branching), n - 1));
  t_end = float(double(t0) * std::pow(double(branching), n));
}

int cascade_count(int width, int height, float t0, int branching) {
  const double diagonal = std::sqrt(double(width) * width + double(height) * height);
  int count = 1;
  while (double(t0) * std::pow(double(branching), count - 1) < diagonal) ++count;
  return count;
}

std::int64_t top_directions(int q0, int branching, int n) {
  std::int64_t q = q0;
  for (int i = 0; i < n && q <= (std::int64_t(1) << 40); ++i) q *= branching;
  return q;
}

void fill_directions(std::vector<Cascade>& plan) {
  for (Cascade& c : plan) {
    c.dir_x.resize(c.directions);
    c.dir_y.resize(c.directions);
    for (int k = 0; k < c.directions; ++k) ray_direction(k, c.directions, c.dir_x[k], c.dir_y[k]);
  }
}

std::vector<Cascade> plan_cascades(int width, int height, const RcOptions& o) {
  const int count =
      o.cascades > 0 ? o.cascades : cascade_count(width, height, o.interval, o.branching);
  std::vector<Cascade> plan(count);
  for (int n = 0; n < count; ++n) {
    Cascade& c = plan[n];
    c.n = n;
    c.spacing = o.probe_spacing << n;
    c.probes_x = (width + c.spacing - 1) / c.spacing;
    c.probes_y = (height + c.spacing - 1) / c.spacing;
    c.directions = int(std::min<std::int64_t>(top_directions(o.directions, o.branching, n),
                                              std::numeric_limits<int>::max()));
    cascade_interval(n, o.interval, o.branching, c.t_begin, c.t_end);
  }
  return plan;
}

std::uint64_t cascade_bytes(const std::vector<Cascade>& plan, const RcOptions& o) {
  std::uint64_t largest = 0;
  for (const Cascade& c : plan) largest = std::max<std::uint64_t>(largest, c.size());
  // Ping-pong: the cascade being merged and the one above it; extension needs a scratch third.
  const int buffers = o.extend ? 3 : 2;
  return largest * buffers * sizeof(Interval);
}

}  // namespace penumbra::flatland::rc
