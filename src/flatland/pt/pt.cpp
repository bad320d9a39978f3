#include "flatland/pt/pt.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <string>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "flatland/trace.hpp"

namespace penumbra::flatland::pt {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// splitmix64's finaliser: a strong 64-bit mix, so hashed keys give independent-looking numbers.
std::uint64_t mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// A uniform number in [0, 1) that depends only on (seed, cell, sample, dimension): the same
// sample gets the same number whatever thread or pass computes it.
double uniform(std::uint64_t seed, std::uint64_t cell, std::uint64_t sample, std::uint64_t dim) {
  const std::uint64_t h = mix(mix(mix(seed ^ mix(cell)) + sample) + dim);
  return double(h >> 11) * 0x1.0p-53;
}

double fract(double v) {
  return v - std::floor(v);
}

// The angular interval an emitter box covers seen from a point, and the probability of picking
// it among the boxes.
struct Arc {
  double start, width, prob;
};

struct Arcs {
  int n = 0;
  std::array<Arc, kMaxEmitterBoxes> arc;
};

// Arcs of every emitter box from (px, py), with picking probabilities proportional to the box's
// radiance times its angular size (the unoccluded light it could send).
void make_arcs(const std::vector<EmitterBox>& boxes, double px, double py, Arcs& out) {
  out.n = 0;
  double total = 0;
  for (const EmitterBox& b : boxes) {
    Arc a;
    if (px >= b.x0 && px <= b.x1 && py >= b.y0 && py <= b.y1) {
      a.start = 0;
      a.width = kTwoPi;
    } else {
      // From outside, the box's silhouette is spanned by two corners that depend only on which
      // side of each slab the point lies: two atan2 instead of four.
      const int sx = px < b.x0 ? 0 : px > b.x1 ? 2 : 1, sy = py < b.y0 ? 0 : py > b.y1 ? 2 : 1;
      // Corner pairs as (x index, y index) into {x0, x1} x {y0, y1}, per (sy, sx).
      static constexpr int kCorners[3][3][4] = {{{0, 1, 1, 0}, {0, 0, 1, 0}, {0, 0, 1, 1}},
                                                {{0, 0, 0, 1}, {0, 0, 0, 0}, {1, 0, 1, 1}},
                                                {{0, 0, 1, 1}, {0, 1, 1, 1}, {0, 1, 1, 0}}};
      const int* k = kCorners[sy][sx];
      const double xs[2] = {double(b.x0), double(b.x1)}, ys[2] = {double(b.y0), double(b.y1)};
      const double a1 = std::atan2(ys[k[1]] - py, xs[k[0]] - px);
      const double a2 = std::atan2(ys[k[3]] - py, xs[k[2]] - px);
      double d = a2 - a1;
      if (d > kTwoPi / 2) d -= kTwoPi;
      if (d < -kTwoPi / 2) d += kTwoPi;
      a.start = d >= 0 ? a1 : a2;
      a.width = std::abs(d);
    }
    a.prob = double(b.radiance) * a.width;
    if (!(a.prob > 0) || !(a.width > 0)) continue;
    total += a.prob;
    out.arc[out.n++] = a;
  }
  for (int k = 0; k < out.n; ++k) out.arc[k].prob /= total;
}

bool in_arc(const Arc& a, double theta) {
  double d = theta - a.start;
  d -= kTwoPi * std::floor(d / kTwoPi);
  return d < a.width;
}

// Maps u in [0, 1) to an angle and returns its probability density. Without arcs: uniform. With
// them (next event estimation): half of [0, 1) samples uniformly and half picks an arc by its
// probability and a uniform angle inside it; the density of this mixture is the one-sample
// balance heuristic of the two strategies, so the estimate stays unbiased wherever either
// strategy reaches. One number drives both choices, so the low-discrepancy sequence still
// stratifies them.
double sample_direction(double u, const Arcs& arcs, double& theta) {
  if (arcs.n == 0) {
    theta = kTwoPi * u;
    return 1.0 / kTwoPi;
  }
  if (u < 0.5) {
    theta = kTwoPi * (2 * u);
  } else {
    double v = 2 * u - 1;
    int k = 0;
    while (k + 1 < arcs.n && v >= arcs.arc[k].prob) v -= arcs.arc[k].prob, ++k;
    const Arc& a = arcs.arc[k];
    const double f = std::clamp(v / a.prob, 0.0, 1.0 - 1e-12);
    theta = a.start + a.width * f;
  }
  double pdf = 0.5 / kTwoPi;
  for (int k = 0; k < arcs.n; ++k)
    if (in_arc(arcs.arc[k], theta)) pdf += 0.5 * arcs.arc[k].prob / arcs.arc[k].width;
  return pdf;
}

float luminance(const Cell& c) {
  return (c.r + c.g + c.b) / 3.0f;
}

struct Context {
  const Medium& medium;
  const float* albedo;  // 3 per cell
  Rgb environment;
  const std::vector<EmitterBox>& emitters;
  PtOptions options;
  int bounces;
};

// One sample of the fluence at cell (cx, cy): a direction from the cell centre and the radiance
// arriving along it (emission and environment, exactly through the cells). With more bounces,
// one cell along the ray that scatters is picked in proportion to its share of the reflected
// light (reservoir sampling, one number), and the fluence at its centre is estimated the same
// way: the estimator of F_N = integral of L with re-emission albedo * F_(N-1) / 2pi, the same
// fixed-point iteration the cascades run.
void sample_cell(const Context& c, int cx, int cy, std::uint64_t cell, std::uint64_t i, double u0,
                 const Arcs& primary, double out[3], std::uint64_t& rays) {
  const Medium& m = c.medium;
  double beta[3] = {1, 1, 1};
  float px = float(cx) + 0.5f, py = float(cy) + 0.5f;
  Arcs local;
  for (int depth = 0; depth < c.bounces; ++depth) {
    const Arcs* arcs = &primary;
    double u = u0;
    if (depth > 0) {
      u = uniform(c.options.seed, cell, i, 2 * std::uint64_t(depth));
      if (c.options.nee) make_arcs(c.emitters, px, py, local);
      arcs = &local;
    }
    double theta;
    const double pdf = sample_direction(u, *arcs, theta);
    const float dx = float(std::cos(theta)), dy = float(std::sin(theta));
    ++rays;
    double radiance[3];
    if (depth + 1 == c.bounces) {
      const Interval iv = trace_interval(m, px, py, dx, dy, 0.0f, kInf, true);
      radiance[0] = iv.r + iv.t * c.environment.r;
      radiance[1] = iv.g + iv.t * c.environment.g;
      radiance[2] = iv.b + iv.t * c.environment.b;
      for (int k = 0; k < 3; ++k) out[k] += beta[k] * radiance[k] / pdf;
      return;
    }
    double pick = uniform(c.options.seed, cell, i, 2 * std::uint64_t(depth) + 1);
    double total = 0;  // sum of the scattering weights seen so far
    std::size_t chosen = std::numeric_limits<std::size_t>::max();
    float t = 1, r = 0, g = 0, b = 0;
    walk_cells(m, px, py, dx, dy, 0.0f, kInf, true,
               [&](std::size_t idx, float step, float t0, float t1) {
                 const Cell& e = m.cells[idx];
                 const float tr = step == kOpaque ? 0.0f : std::exp(-step * (t1 - t0));
                 const float w = t * (1.0f - tr);  // this cell's share of what arrives
                 r += w * e.r;
                 g += w * e.g;
                 b += w * e.b;
                 const float* a = c.albedo + 3 * idx;
                 const double q = double(w) * std::max({a[0], a[1], a[2]});
                 if (q > 0) {
                   total += q;
                   const double p = q / total;
                   if (pick < p) {
                     chosen = idx;
                     pick /= p;
                   } else {
                     pick = (pick - p) / (1 - p);
                   }
                 }
                 t *= tr;
                 return t > 0.0f;
               });
    radiance[0] = r + t * c.environment.r;
    radiance[1] = g + t * c.environment.g;
    radiance[2] = b + t * c.environment.b;
    for (int k = 0; k < 3; ++k) out[k] += beta[k] * radiance[k] / pdf;
    if (chosen == std::numeric_limits<std::size_t>::max()) return;
    const float* a = c.albedo + 3 * chosen;
    const double scale = total / (double(std::max({a[0], a[1], a[2]})) * kTwoPi * pdf);
    for (int k = 0; k < 3; ++k) beta[k] *= a[k] * scale;
    px = float(chosen % std::size_t(m.width)) + 0.5f;
    py = float(chosen / std::size_t(m.width)) + 0.5f;
  }
}

// Adds samples [first, first + count) of every cell to `sum`, each cell's in sample order.
std::uint64_t run_pass(const Context& c, std::uint64_t first, std::uint64_t count,
                       std::vector<double>& sum) {
  const Medium& m = c.medium;
  std::vector<std::uint64_t> rays(std::size_t(m.height), 0);
  constexpr double kGolden = 0.61803398874989484820;  // R1: the inverse golden ratio
  parallel_for(m.height, [&](int y) {
    Arcs primary;
    std::uint64_t row_rays = 0;
    for (int x = 0; x < m.width; ++x) {
      const std::uint64_t cell = std::uint64_t(y) * std::uint64_t(m.width) + std::uint64_t(x);
      if (c.options.nee) make_arcs(c.emitters, x + 0.5, y + 0.5, primary);
      const double rotation = uniform(c.options.seed, cell, ~std::uint64_t(0), 0);
      double* s = &sum[3 * cell];
      for (std::uint64_t i = first; i < first + count; ++i) {
        const double u0 = c.options.sampler == Sampler::r1
                              ? fract(rotation + fract(double(i) * kGolden))
                              : uniform(c.options.seed, cell, i, 0);
        double f[3] = {0, 0, 0};
        sample_cell(c, x, y, cell, i, u0, primary, f, row_rays);
        s[0] += f[0];
        s[1] += f[1];
        s[2] += f[2];
      }
    }
    rays[std::size_t(y)] = row_rays;
  });
  return std::accumulate(rays.begin(), rays.end(), std::uint64_t(0));
}

}  // namespace

std::vector<EmitterBox> find_emitters(const Medium& m) {
  const int w = m.width, h = m.height;
  const std::size_t n = std::size_t(w) * h;
  // Union-find over emitting cells; -1 marks cells that do not emit.
  std::vector<std::int32_t> parent(n, -1);
  auto emits = [&](std::size_t i) { return m.step[i] > 0 && luminance(m.cells[i]) > 0; };
  auto find = [&](std::int32_t i) {
    while (parent[std::size_t(i)] != i) {
      parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];
      i = parent[std::size_t(i)];
    }
    return i;
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      if (!emits(i)) continue;
      parent[i] = std::int32_t(i);
      // Already-visited 8-neighbours: left, and the three above.
      const int nx[4] = {x - 1, x - 1, x, x + 1}, ny[4] = {y, y - 1, y - 1, y - 1};
      for (int k = 0; k < 4; ++k) {
        if (nx[k] < 0 || nx[k] >= w || ny[k] < 0) continue;
        const std::size_t j = std::size_t(ny[k]) * w + nx[k];
        if (parent[j] < 0) continue;
        const std::int32_t a = find(std::int32_t(i)), b = find(std::int32_t(j));
        if (a != b) parent[std::size_t(std::max(a, b))] = std::min(a, b);
      }
    }
  struct Group {
    int x0, y0, x1, y1;
    double power;
  };
  std::map<std::int32_t, Group> groups;  // ordered by root: deterministic
  for (std::size_t i = 0; i < n; ++i) {
    if (parent[i] < 0) continue;
    const int x = int(i % std::size_t(w)), y = int(i / std::size_t(w));
    auto [it, fresh] = groups.try_emplace(find(std::int32_t(i)), Group{x, y, x + 1, y + 1, 0.0});
    Group& g = it->second;
    g.x0 = std::min(g.x0, x), g.y0 = std::min(g.y0, y);
    g.x1 = std::max(g.x1, x + 1), g.y1 = std::max(g.y1, y + 1);
    g.power += luminance(m.cells[i]);
  }
  std::vector<Group> merged;
  for (const auto& [root, g] : groups) merged.push_back(g);
  for (int tile = 32; int(merged.size()) > kMaxEmitterBoxes; tile *= 2) {
    std::map<std::pair<int, int>, Group> tiles;
    for (const auto& [root, g] : groups) {
      const std::pair<int, int> key{(g.x0 + g.x1) / 2 / tile, (g.y0 + g.y1) / 2 / tile};
      auto [it, fresh] = tiles.try_emplace(key, g);
      if (fresh) continue;
      Group& t = it->second;
      t.x0 = std::min(t.x0, g.x0), t.y0 = std::min(t.y0, g.y0);
      t.x1 = std::max(t.x1, g.x1), t.y1 = std::max(t.y1, g.y1);
      t.power += g.power;
    }
    merged.clear();
    for (const auto& [key, g] : tiles) merged.push_back(g);
  }
  std::vector<EmitterBox> boxes;
  for (const Group& g : merged)
    boxes.push_back(
        {g.x0, g.y0, g.x1, g.y1, float(g.power / (double(g.x1 - g.x0) * double(g.y1 - g.y0)))});
  return boxes;
}

std::uint64_t working_bytes(int width, int height, const PtOptions& options) {
  const std::uint64_t cells = std::uint64_t(width) * std::uint64_t(height);
  std::uint64_t bytes = cells * 3 * (sizeof(double) + sizeof(float));  // sums and fluence
  if (options.nee) bytes += cells * sizeof(std::int32_t);              // emitter labels
  return bytes;
}

std::vector<float> solve(const Medium& medium, const std::vector<float>& albedo,
                         const Rgb& environment, const RenderOptions& options,
                         RenderResult& result) {
  const PtOptions& o = options.pt;
  Stopwatch watch;
  std::vector<EmitterBox> emitters;
  if (o.nee) {
    emitters = find_emitters(medium);
    result.stages.push_back({"emitters", watch.ms()});
  }
  const Context context{medium, albedo.data(), environment, emitters, o, options.bounces};
  const std::size_t cells = std::size_t(medium.width) * std::size_t(medium.height);
  std::vector<double> sum(3 * cells, 0.0);

  // Passes of `count` samples per cell, sized to take about half a second each so progress
  // and cancelling respond, and to end near the time limit.
  watch.restart();
  const std::uint64_t target = std::uint64_t(std::max(o.spp, 0));
  const double limit_s = o.seconds > 0 ? o.seconds : std::numeric_limits<double>::infinity();
  std::uint64_t done = 0, count = 1;
  while (true) {
    if (target > 0) count = std::min(count, target - done);
    Stopwatch pass;
    result.intervals += run_pass(context, done, count, sum);
    done += count;
    const double elapsed = watch.ms() / 1e3;
    const double per_sample = pass.ms() / 1e3 / double(count);
    const bool time_up = elapsed >= limit_s;
    if (options.progress) {
      RenderProgress p{done, target, elapsed, 0.0};
      p.fraction = target > 0 ? double(done) / double(target) : 0.0;
      if (o.seconds > 0) p.fraction = std::max(p.fraction, std::min(1.0, elapsed / limit_s));
      options.progress(p);
    }
    if ((target > 0 && done >= target) || time_up) break;
    if (options.cancel && options.cancel->load()) {
      result.cancelled = true;
      break;
    }
    double budget = 0.5;
    if (o.seconds > 0) budget = std::min(budget, limit_s - elapsed);
    count = std::uint64_t(std::clamp(budget / std::max(per_sample, 1e-9), 1.0, 1e9));
  }
  result.stages.push_back({"samples", watch.ms()});
  result.samples = done;

  std::vector<float> fluence(3 * cells);
  const double inv = 1.0 / double(done);
  parallel_for(medium.height, [&](int y) {
    for (std::size_t i = std::size_t(y) * medium.width * 3;
         i < std::size_t(y + 1) * medium.width * 3; ++i)
      fluence[i] = float(sum[i] * inv);
  });
  return fluence;
}

}  // namespace penumbra::flatland::pt
