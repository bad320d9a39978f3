// Gather and merge of flatland radiance cascades, top down, two cascades alive at a time.
#include "flatland/rc/rc.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/huge_pages.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "flatland/interval.hpp"
#include "flatland/trace.hpp"

namespace penumbra::flatland::rc {

namespace {

// The four probes of a cascade around a position, with bilinear weights; probe a of the 2x2
// block is (x[a & 1], y[a >> 1]). Indices are clamped at the grid's edge.
struct Footprint {
  int x[2], y[2];
  float w[4];
};

Footprint bilinear(const Cascade& c, float px, float py) {
  const float u = px / float(c.spacing) - 0.5f, v = py / float(c.spacing) - 0.5f;
  const float fu0 = std::floor(u), fv0 = std::floor(v);
  const float fu = u - fu0, fv = v - fv0;
  const int i0 = int(fu0), j0 = int(fv0);
  Footprint f;
  f.x[0] = std::clamp(i0, 0, c.probes_x - 1);
  f.x[1] = std::clamp(i0 + 1, 0, c.probes_x - 1);
  f.y[0] = std::clamp(j0, 0, c.probes_y - 1);
  f.y[1] = std::clamp(j0 + 1, 0, c.probes_y - 1);
  f.w[0] = (1 - fu) * (1 - fv);
  f.w[1] = fu * (1 - fv);
  f.w[2] = (1 - fu) * fv;
  f.w[3] = fu * fv;
  return f;
}

// The environment lies beyond the last interval (seed 004, footnote 1, for cascades too).
Interval merge_sky(const Interval& near, const Rgb& env) {
  return merge_intervals(near, Interval{env.r, env.g, env.b, 0.0f});
}

// Everything a kernel of cascade n reads.
struct Level {
  const Medium& medium;
  const Cascade& c;
  const Cascade* up;      // cascade n+1, null for the top cascade
  const Interval* upper;  // merged cascade n+1 (direction-first), null for the top cascade
  const RcOptions& o;
  Rgb environment;
  bool skip_start;  // cascade-0 rays leave the opaque cell they start in (see trace.hpp)
};

// Radiance of direction k at a position, merged with everything beyond (cascades above and
// the sky). `near` is the cascade-n interval when it was built already (by extension).
Interval merged_radiance(const Level& L, int k, float px, float py, const Interval* near) {
  const Cascade& c = L.c;
  auto trace_near = [&] {
    return near ? *near
                : trace_interval(L.medium, px, py, c.dir_x[k], c.dir_y[k], c.t_begin, c.t_end,
                                 L.skip_start);
  };
  if (!L.up) return merge_sky(trace_near(), L.environment);

  const Cascade& u = *L.up;
  const int b = L.o.branching;
  const float inv_b = 1.0f / float(b);
  Interval far = zero_interval();
  switch (L.o.fix) {
    case MergeFix::bilinear: {
      // Each child ray runs from this probe's interval start to the start of the interval of
      // each of the 4 upper probes, so no interval is skipped or counted twice.
      Interval sum = zero_interval();
      const Footprint f = bilinear(u, px, py);
      for (int ci = 0; ci < b; ++ci) {
        const int kk = b * k + ci;
        const float dx = u.dir_x[kk], dy = u.dir_y[kk];
        for (int a = 0; a < 4; ++a) {
          if (f.w[a] == 0.0f) continue;
          const int qi = f.x[a & 1], qj = f.y[a >> 1];
          const Interval seg = trace_segment(L.medium, px + dx * c.t_begin, py + dy * c.t_begin,
                                             u.probe_x(qi) + dx * u.t_begin,
                                             u.probe_y(qj) + dy * u.t_begin, L.skip_start);
          accumulate(sum, merge_intervals(seg, L.upper[u.index(kk, qi, qj)]), f.w[a] * inv_b);
        }
      }
      return sum;
    }
    case MergeFix::none: {
      const Footprint f = bilinear(u, px, py);
      for (int ci = 0; ci < b; ++ci)
        for (int a = 0; a < 4; ++a)
          accumulate(far, L.upper[u.index(b * k + ci, f.x[a & 1], f.y[a >> 1])], f.w[a] * inv_b);
      break;
    }
    case MergeFix::nearest: {
      const int qi = std::clamp(int(std::floor(px / float(u.spacing))), 0, u.probes_x - 1);
      const int qj = std::clamp(int(std::floor(py / float(u.spacing))), 0, u.probes_y - 1);
      for (int ci = 0; ci < b; ++ci) accumulate(far, L.upper[u.index(b * k + ci, qi, qj)], inv_b);
      break;
    }
  }
  return merge_intervals(trace_near(), far);
}

// Fills cascade n (merged with everything above) into `out`.
void merge_cascade(const Level& L, Interval* out, const Interval* near) {
  const Cascade& c = L.c;
  parallel_for(c.directions * c.probes_y, [&](int row) {
    const int k = row / c.probes_y, j = row % c.probes_y;
    const float py = c.probe_y(j);
    const float h = 0.25f * float(c.spacing);
    for (int i = 0; i < c.probes_x; ++i) {
      const float px = c.probe_x(i);
      const std::size_t idx = c.index(k, i, j);
      if (L.o.preaverage) {
        // Pre-averaging (seed 000, section 5.1): the 2x2 sub-probes of a probe, averaged.
        Interval v = zero_interval();
        for (int a = 0; a < 4; ++a)
          accumulate(v,
                     merged_radiance(L, k, px + (a & 1 ? h : -h), py + (a & 2 ? h : -h), nullptr),
                     0.25f);
        out[idx] = v;
      } else {
        out[idx] = merged_radiance(L, k, px, py, near ? &near[idx] : nullptr);
      }
    }
  });
}

// Interval [a, a+len] of direction k seen from an arbitrary position: interpolated from the
// probe grid of `field` when the position lies inside it, traced exactly otherwise (outside the
// grid the trace is clipped, so a ray leaving the scene costs nothing).
Interval shifted_interval(const Medium& m, const Cascade& c, const Interval* field, int k, float qx,
                          float qy, float a, float len) {
  const float u = qx / float(c.spacing) - 0.5f, v = qy / float(c.spacing) - 0.5f;
  if (u >= 0 && v >= 0 && u <= float(c.probes_x - 1) && v <= float(c.probes_y - 1)) {
    const Footprint f = bilinear(c, qx, qy);
    Interval s = zero_interval();
    for (int q = 0; q < 4; ++q) accumulate(s, field[c.index(k, f.x[q & 1], f.y[q >> 1])], f.w[q]);
    return s;
  }
  return trace_interval(m, qx, qy, c.dir_x[k], c.dir_y[k], a, a + len);
}

// Interval extension (seed 001 eq. 16, "Radiant 2d"): trace [t_n, t_n + x] at every probe, then
// double it m times with L_{a,a+2x}(p) = L_{a,a+x}(p) merged with L_{a,a+x}(p + x w).
// Returns whichever of the two buffers holds the result.
Interval* extend_intervals(const Medium& m, const Cascade& c, float piece, bool skip_start,
                           Interval* a, Interval* b) {
  float x = c.t_end - c.t_begin;
  int doublings = 0;
  while (x > piece) x *= 0.5f, ++doublings;
  parallel_for(c.directions * c.probes_y, [&](int row) {
    const int k = row / c.probes_y, j = row % c.probes_y;
    for (int i = 0; i < c.probes_x; ++i)
      a[c.index(k, i, j)] = trace_interval(m, c.probe_x(i), c.probe_y(j), c.dir_x[k], c.dir_y[k],
                                           c.t_begin, c.t_begin + x, skip_start);
  });
  for (int d = 0; d < doublings; ++d, x *= 2.0f) {
    parallel_for(c.directions * c.probes_y, [&](int row) {
      const int k = row / c.probes_y, j = row % c.probes_y;
      for (int i = 0; i < c.probes_x; ++i) {
        const float qx = c.probe_x(i) + c.dir_x[k] * x, qy = c.probe_y(j) + c.dir_y[k] * x;
        const std::size_t idx = c.index(k, i, j);
        b[idx] = merge_intervals(a[idx], shifted_interval(m, c, a, k, qx, qy, c.t_begin, x));
      }
    });
    std::swap(a, b);
  }
  return a;
}

// Fluence F = sum over the Q0 cones of 2pi/Q0 * radiance, at every cell centre, from the probes
// of merged cascade 0 that the cell can see (visibility-weighted bilinear), so light does not
// leak through walls thinner than the probe spacing.
std::vector<float> fluence(const Medium& m, const Cascade& c0, const Interval* r0) {
  std::vector<float> out;
  reserve_huge(out, std::size_t(m.width) * m.height * 3);
  out.resize(std::size_t(m.width) * m.height * 3);
  const float cone = float(kTwoPi / c0.directions);
  parallel_for(m.height, [&](int y) {
    for (int x = 0; x < m.width; ++x) {
      const float cx = float(x) + 0.5f, cy = float(y) + 0.5f;
      const Footprint f = bilinear(c0, cx, cy);
      float w[4], total = 0;
      for (int a = 0; a < 4; ++a) {
        w[a] = f.w[a];
        if (w[a] == 0.0f) continue;
        w[a] *= trace_segment(m, cx, cy, c0.probe_x(f.x[a & 1]), c0.probe_y(f.y[a >> 1]), true).t;
        total += w[a];
      }
      // A cell that sees none of its probes (sealed in) falls back to plain interpolation.
      const float* wt = total > 1e-6f ? w : f.w;
      const float norm = total > 1e-6f ? 1.0f / total : 1.0f;
      float r = 0, g = 0, bl = 0;
      for (int k = 0; k < c0.directions; ++k)
        for (int a = 0; a < 4; ++a) {
          if (wt[a] == 0.0f) continue;
          const Interval& v = r0[c0.index(k, f.x[a & 1], f.y[a >> 1])];
          r += wt[a] * v.r;
          g += wt[a] * v.g;
          bl += wt[a] * v.b;
        }
      float* o = &out[(std::size_t(y) * m.width + x) * 3];
      o[0] = r * norm * cone;
      o[1] = g * norm * cone;
      o[2] = bl * norm * cone;
    }
  });
  return out;
}

}  // namespace

std::uint64_t traced_intervals(const std::vector<Cascade>& plan, const RcOptions& o) {
  std::uint64_t total = 0;
  for (const Cascade& c : plan) {
    const bool top = c.n + 1 == int(plan.size());
    std::uint64_t per = 1;
    if (!top && o.fix == MergeFix::bilinear) per = std::uint64_t(o.branching) * 4;
    if (o.preaverage) per *= 4;
    total += per * c.size();
  }
  return total;
}

std::vector<float> solve(const Medium& medium, const Rgb& environment,
                         const std::vector<Cascade>& plan, const RcOptions& o,
                         std::vector<StageTime>& stages) {
  std::size_t largest = 0;
  for (const Cascade& c : plan) largest = std::max(largest, c.size());
  std::vector<Interval> buffers[3];
  const int count = o.extend ? 3 : 2;
  for (int i = 0; i < count; ++i) buffers[i].resize(largest);

  Interval* upper = nullptr;
  for (int n = int(plan.size()) - 1; n >= 0; --n) {
    Stopwatch watch;
    const Cascade& c = plan[n];
    // The buffers not holding the cascade above are free for this one.
    Interval* free_buf[2];
    int f = 0;
    for (int i = 0; i < count && f < 2; ++i)
      if (buffers[i].data() != upper) free_buf[f++] = buffers[i].data();
    const Level level{medium, c, n + 1 < int(plan.size()) ? &plan[n + 1] : nullptr,
                      upper,  o, environment,
                      n == 0};
    Interval* out = free_buf[0];
    const Interval* near = nullptr;
    if (o.extend && c.t_end - c.t_begin > o.extend_length) {
      out = extend_intervals(medium, c, o.extend_length, n == 0, free_buf[0], free_buf[1]);
      near = out;  // merged in place: each probe reads its own interval, then overwrites it
    }
    merge_cascade(level, out, near);
    upper = out;
    stages.push_back({"cascade " + std::to_string(n), watch.ms()});
  }
  Stopwatch watch;
  std::vector<float> f = fluence(medium, plan[0], upper);
  stages.push_back({"fluence", watch.ms()});
  return f;
}

}  // namespace penumbra::flatland::rc
