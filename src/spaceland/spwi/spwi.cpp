#include "spaceland/spwi/spwi.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/math.hpp"
#include "core/octahedral.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/camera.hpp"
#include "spaceland/color.hpp"
#include "spaceland/grid/grid.hpp"
#include "spaceland/probe_light.hpp"

namespace penumbra::spaceland::spwi {

namespace {

constexpr int kMaxCascades = 12;

// The most cascades worth having on a w x h image: until the probe spacing reaches the image's
// diagonal (one probe for the whole screen). Past it a cascade only multiplies its directions.
// `step`: the spacing grows by 2^step per cascade.
int screen_cascades(int w, int h, int s0, int step) {
  const double diagonal = std::sqrt(double(w) * w + double(h) * h);
  int n = 1;
  while (n < kMaxCascades / step && double(s0) * double(1 << (step * (n - 1))) < diagonal) ++n;
  return n;
}

// A probe: a visible surface point under the pixel at the centre of its tile.
struct Probe {
  Vec3 p, n;        // position (depth bias applied) and the surface's normal, faced to the camera
  float depth = 0;  // linear depth
  bool valid = false;  // false where the pixel sees the sky
};

// Screen position of probe index k along an axis (the centre of the pixel at the tile's middle).
double probe_x(int k, int spacing) {
  return double(k) * spacing + spacing / 2 + 0.5;
}

// The 4 probes of a grid around the screen point (x, y) and their bilinear weights, corners in
// the order (0, 0), (1, 0), (0, 1), (1, 1) (Alg. 8's srcPoints order).
struct Corners {
  std::array<int, 8> index{};  // probes; 8 with the min-max merge (2 per tile)
  std::array<float, 8> w{};
  int n = 4;
  float fx = 0, fy = 0;
};

Corners corners(double x, double y, int spacing, int nx, int ny) {
  auto axis = [&](double c, int n, int& base, float& f) {
    const double g = (c - (spacing / 2 + 0.5)) / spacing;
    base = int(std::floor(g));
    f = float(g - base);
    if (n == 1) {
      base = 0;
      f = 0;
    } else if (base < 0) {
      base = 0;
      f = 0;
    } else if (base >= n - 1) {
      base = n - 2;
      f = 1;
    }
  };
  int bx, by;
  Corners c;
  axis(x, nx, bx, c.fx);
  axis(y, ny, by, c.fy);
  const int bx1 = std::min(bx + 1, nx - 1), by1 = std::min(by + 1, ny - 1);
  c.index = {by * nx + bx, by * nx + bx1, by1 * nx + bx, by1 * nx + bx1};
  c.w = {(1 - c.fx) * (1 - c.fy), c.fx * (1 - c.fy), (1 - c.fx) * c.fy, c.fx * c.fy};
  c.n = 4;
  return c;
}

// Bilateral weighting (seed 000 Alg. 7 and 11): on a depth edge among the valid probes (their
// depth range over their mean above `edge`), each weight is divided by the probe's depth
// difference to the point.
void bilateral(Corners& c, const std::vector<Probe>& probes, float depth, float edge) {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo, sum = 0;
  int n = 0;
  for (int k = 0; k < c.n; ++k) {
    if (c.w[std::size_t(k)] <= 0) continue;
    const float d = probes[std::size_t(c.index[std::size_t(k)])].depth;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
    sum += d;
    ++n;
  }
  if (n < 2 || !((hi - lo) / (sum / float(n)) > edge)) return;
  for (int k = 0; k < c.n; ++k) {
    if (c.w[std::size_t(k)] <= 0) continue;
    const float d = probes[std::size_t(c.index[std::size_t(k)])].depth;
    c.w[std::size_t(k)] /= std::abs(d - depth) + 1e-4f;
  }
}

// Where the projection of p falls along the line a -> b, as a fraction in [0, 1].
float project(Vec3 a, Vec3 b, Vec3 p) {
  const Vec3 ab = b - a;
  const float len2 = dot(ab, ab);
  if (!(len2 > 0)) return 0.5f;
  return std::clamp(dot(p - a, ab) / len2, 0.0f, 1.0f);
}

Vec3 mix(Vec3 a, Vec3 b, float t) {
  return a + (b - a) * t;
}

// Seed 000 Alg. 8: the bilinear ratios refined by projecting the point onto the lines between
// the 4 probes in world space (two iterations), starting from the screen-space ratios.
void bilinear3d(Corners& c, const std::vector<Probe>& probes, Vec3 point) {
  const Vec3 s[4] = {probes[std::size_t(c.index[0])].p, probes[std::size_t(c.index[1])].p,
                     probes[std::size_t(c.index[2])].p, probes[std::size_t(c.index[3])].p};
  float rx = c.fx, ry = c.fy;
  for (int it = 0; it < 2; ++it) {
    rx = project(mix(s[0], s[2], ry), mix(s[1], s[3], ry), point);
    ry = project(mix(s[0], s[1], rx), mix(s[2], s[3], rx), point);
  }
  c.w = {(1 - rx) * (1 - ry), rx * (1 - ry), (1 - rx) * ry, rx * ry};
}

// Zero weights of probes on the sky, then normalise; false when no probe is left.
bool normalise(Corners& c, const std::vector<Probe>& probes) {
  float sum = 0;
  for (int k = 0; k < c.n; ++k) {
    if (!probes[std::size_t(c.index[std::size_t(k)])].valid) c.w[std::size_t(k)] = 0;
    sum += c.w[std::size_t(k)];
  }
  if (!(sum > 0)) return false;
  for (int k = 0; k < c.n; ++k) c.w[std::size_t(k)] /= sum;
  return true;
}

// Corners with sky probes left out before the depth weights look at them.
Corners valid_corners(double x, double y, int spacing, int nx, int ny,
                      const std::vector<Probe>& probes) {
  Corners c = corners(x, y, spacing, nx, ny);
  for (int k = 0; k < 4; ++k)
    if (!probes[std::size_t(c.index[std::size_t(k)])].valid) c.w[std::size_t(k)] = 0;
  return c;
}

// A probe on the surface pixel (x, y) sees, if it sees one.
Probe probe_at(const Scene& scene, const GBuffer& g, int x, int y, float depth_bias) {
  Probe p;
  x = std::min(x, g.width - 1);
  y = std::min(y, g.height - 1);
  const std::size_t k = std::size_t(y) * g.width + x;
  if (!g.found[k]) return p;
  const Hit& h = g.hits[k];
  const Vec3 eye = scene.camera.position;
  p.valid = true;
  p.p = eye + (h.position - eye) * depth_bias;
  p.n = h.geometric_normal;
  p.depth = g.linear_depth(k);
  return p;
}

// The 2x2 sub-probes of each tile of cascade i, at the middles of its quarters (pre-averaging).
std::vector<std::array<Probe, 4>> place_sub_probes(const Scene& scene, const GBuffer& g,
                                                   const Plan& plan, int i, float depth_bias) {
  const int s = plan.spacing(i), nx = plan.nx[std::size_t(i)], ny = plan.ny[std::size_t(i)];
  const int q1 = s / 4, q3 = (3 * s) / 4;
  std::vector<std::array<Probe, 4>> subs(std::size_t(nx) * ny);
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) {
      std::array<Probe, 4>& sp = subs[std::size_t(y) * nx + x];
      sp[0] = probe_at(scene, g, x * s + q1, y * s + q1, depth_bias);
      sp[1] = probe_at(scene, g, x * s + q3, y * s + q1, depth_bias);
      sp[2] = probe_at(scene, g, x * s + q1, y * s + q3, depth_bias);
      sp[3] = probe_at(scene, g, x * s + q3, y * s + q3, depth_bias);
    }
  return subs;
}

// The min-max merge (seed 000 chapter 7): each tile of the cascade above has a probe on the
// nearest and one on the farthest surface in it; a point at `depth` takes each tile's two by
// linear interpolation in depth between them (trilinear with the screen's bilinear weights).
// `c` holds tile indices; probes are 2 per tile (min, max).
Corners minmax_corners(const Corners& c, const std::vector<Probe>& probes, float depth) {
  Corners out;
  out.n = 0;
  for (int k = 0; k < 4; ++k) {
    const float w = c.w[std::size_t(k)];
    if (w <= 0) continue;
    const int lo = 2 * c.index[std::size_t(k)], hi = lo + 1;
    const Probe &a = probes[std::size_t(lo)], &b = probes[std::size_t(hi)];
    if (!a.valid && !b.valid) continue;
    float t = 0.5f;
    if (a.valid && b.valid) {
      const float span = b.depth - a.depth;
      t = span > 0 ? std::clamp((depth - a.depth) / span, 0.0f, 1.0f) : 0.5f;
    } else {
      t = b.valid ? 1.0f : 0.0f;
    }
    out.index[std::size_t(out.n)] = lo;
    out.w[std::size_t(out.n++)] = w * (1 - t);
    out.index[std::size_t(out.n)] = hi;
    out.w[std::size_t(out.n++)] = w * t;
  }
  if (out.n == 0) {  // no tile with a surface: an entry of weight 0 that normalise refuses
    out.n = 1;
    out.index[0] = 2 * c.index[0];
    out.w[0] = 0;
  }
  return out;
}

// With the min-max merge: per tile, probes on the nearest and the farthest surface pixel of the
// tile (the min-max depth pyramid's level of this cascade, read directly off the G-buffer).
std::vector<Probe> place_minmax_probes(const Scene& scene, const GBuffer& g, const Plan& plan,
                                       int i, float depth_bias) {
  const int s = plan.spacing(i), nx = plan.nx[std::size_t(i)], ny = plan.ny[std::size_t(i)];
  std::vector<Probe> probes(std::size_t(nx) * ny * 2);
  parallel_for(ny, [&](int ty) {
    for (int tx = 0; tx < nx; ++tx) {
      float lo = std::numeric_limits<float>::infinity(), hi = -lo;
      int lx = -1, ly = -1, hx = -1, hy = -1;
      for (int y = ty * s; y < std::min((ty + 1) * s, g.height); ++y)
        for (int x = tx * s; x < std::min((tx + 1) * s, g.width); ++x) {
          const std::size_t k = std::size_t(y) * g.width + x;
          if (!g.found[k]) continue;
          const float d = g.linear_depth(k);
          if (d < lo) {
            lo = d;
            lx = x;
            ly = y;
          }
          if (d > hi) {
            hi = d;
            hx = x;
            hy = y;
          }
        }
      const std::size_t t = std::size_t(ty) * nx + tx;
      if (lx < 0) continue;
      probes[2 * t] = probe_at(scene, g, lx, ly, depth_bias);
      probes[2 * t + 1] = probe_at(scene, g, hx, hy, depth_bias);
    }
  });
  return probes;
}

// The probes of cascade i on the G-buffer.
std::vector<Probe> place_probes(const Scene& scene, const GBuffer& g, const Plan& plan, int i,
                                float depth_bias) {
  const int s = plan.spacing(i), nx = plan.nx[std::size_t(i)], ny = plan.ny[std::size_t(i)];
  std::vector<Probe> probes(std::size_t(nx) * ny);
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x)
      probes[std::size_t(y) * nx + x] =
          probe_at(scene, g, x * s + s / 2, y * s + s / 2, depth_bias);
  return probes;
}

// What a ray that leaves the scene sees from the top cascade: the sky, with the sun's disk when
// the cascades carry the sun.
Rgb top_background(const Background& bg, Vec3 d, SpwiSun sun) {
  return sun == SpwiSun::cascades ? bg(d) : bg.sky(d);
}

}  // namespace

std::uint64_t Plan::bytes() const {
  std::uint64_t largest = 0, probe_bytes = 0;
  for (int i = 0; i < cascades; ++i) {
    largest = std::max(largest, rays(i));
    probe_bytes += probes(i) * sizeof(Probe) * (preaverage ? 5 : 1);
  }
  // Plus cascade 0's per-probe means (--gather probe), counted either way: 12 B a probe.
  return 2 * largest * sizeof(Rgb) + probe_bytes + (cascades > 0 ? probes(0) * sizeof(Rgb) : 0);
}

namespace {

// What the options fix of a plan for a w x h image (no t0, no cascade count, no grids yet).
Plan options_plan(int width, int height, const SpwiOptions& o) {
  Plan p;
  p.width = width;
  p.height = height;
  p.probe_spacing = std::max(1, o.probe_spacing);
  p.side = std::max(1, int(std::lround(std::sqrt(double(std::max(1, o.directions))))));
  p.preaverage = o.preaverage;
  p.layers = o.merge == SpwiMerge::minmax ? 2 : 1;
  p.step = o.branching == 16 ? 2 : 1;
  return p;
}

// The probe grid of each of the plan's cascades.
void add_grids(Plan& p) {
  for (int i = 0; i < p.cascades; ++i) {
    p.nx.push_back((p.width + p.spacing(i) - 1) / p.spacing(i));
    p.ny.push_back((p.height + p.spacing(i) - 1) / p.spacing(i));
  }
}

}  // namespace

std::uint64_t bytes_upper_bound(int width, int height, const SpwiOptions& o) {
  Plan p = options_plan(width, height, o);
  p.cascades = o.cascades > 0 ? std::min(o.cascades, kMaxCascades / p.step)
                              : screen_cascades(width, height, p.probe_spacing, p.step);
  add_grids(p);
  return p.bytes();
}

Status check_options(const SpwiOptions& o) {
  if (o.probe_spacing < 1 || o.probe_spacing > 64)
    return Error{"`spwi.probe_spacing`: expected 1..64, found " + std::to_string(o.probe_spacing)};
  const int side = int(std::lround(std::sqrt(double(std::max(0, o.directions)))));
  if (o.directions < 4 || side * side != o.directions || (side & (side - 1)) != 0)
    return Error{
        "`spwi.directions`: expected the square of a power of two (4, 16, 64, ...), "
        "found " +
        std::to_string(o.directions)};
  if (!std::isfinite(o.interval) || o.interval < 0)
    return Error{"`spwi.interval`: expected a length > 0 in world units (0: derived), found " +
                 io::format_number(o.interval)};
  if (o.branching != 4 && o.branching != 16)
    return Error{
        "`spwi.branching`: expected 4 or 16 (directions per cascade multiply by it, "
        "the octahedral map's side by 2 or 4), found " +
        std::to_string(o.branching)};
  const int most = o.branching == 16 ? kMaxCascades / 2 : kMaxCascades;
  if (o.cascades < 0 || o.cascades > most)
    return Error{"`spwi.cascades`: expected 0.." + std::to_string(most) + " with branching " +
                 std::to_string(o.branching) + " (0: derived), found " +
                 std::to_string(o.cascades)};
  if (!(o.depth_bias > 0 && o.depth_bias <= 1))
    return Error{"`spwi.depth_bias`: expected a fraction in (0, 1], found " +
                 io::format_number(o.depth_bias)};
  if (!(o.merge_edge >= 0) || !(o.gather_edge >= 0) || !std::isfinite(o.merge_edge) ||
      !std::isfinite(o.gather_edge))
    return Error{"`spwi.merge_edge` and `spwi.gather_edge`: expected numbers >= 0"};
  if (o.preaverage && o.merge == SpwiMerge::minmax)
    return Error{
        "`spwi.preaverage` does not combine with the min-max merge yet: use one or the "
        "other"};
  if (!(o.gather_normal >= 0 && o.gather_normal <= 64))
    return Error{"`spwi.gather_normal`: expected an exponent in [0, 64], found " +
                 io::format_number(o.gather_normal)};
  return {};
}

// The options are check_options', which render() runs before any scene.
Status check(const Scene& scene, const RenderOptions&) {
  if (!scene.media.empty())
    return Error{"spwi cannot carry fog: the scene has " + std::to_string(scene.media.size()) +
                 " medium box(es); use --method pt"};
  return {};
}

namespace {

// The plan, with t0 and the cascade count derived where the options leave them to 0.
Plan make_plan(const Scene& scene, const GBuffer& g, const SpwiOptions& o) {
  Plan p = options_plan(g.width, g.height, o);
  p.t0 = o.interval;
  if (!(p.t0 > 0)) {
    // Four times the world size of s0 pixels at the median depth of the visible surfaces. One
    // probe spacing (the penumbra condition's balance at the median depth) was measured too
    // short: probes on farther surfaces are further apart, and small lights need cascade 0's
    // finer directions to reach them. 4x is the best or near it on 8 of 9 scenes
    // (docs/QUALITY.md, "SPWI against the path tracer: the study").
    std::vector<float> depths;
    for (std::size_t k = 0; k < g.hits.size(); ++k)
      if (g.found[k]) depths.push_back(g.linear_depth(k));
    float median = 1;
    if (!depths.empty()) {
      std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
      median = depths[depths.size() / 2];
    }
    const double pixel = 2 * median * std::tan(double(scene.camera.fov_y) * kPi / 360) / g.height;
    p.t0 = float(std::max(1e-6, 4 * pixel * o.probe_spacing));
  }
  p.cascades = o.cascades;
  if (p.cascades == 0) {
    // Enough that the last interval reaches across the scene's bounds and the camera.
    Bounds b = scene_bounds(scene);
    b.lo = min(b.lo, scene.camera.position);
    b.hi = max(b.hi, scene.camera.position);
    const double reach = length(b.hi - b.lo);
    const int most = screen_cascades(g.width, g.height, p.probe_spacing, p.step);
    p.cascades = 1;
    while (p.cascades < most && double(p.interval_end(p.cascades - 1)) < reach) ++p.cascades;
  }
  add_grids(p);
  return p;
}

std::string mib(std::uint64_t bytes) {
  return io::format_rounded(double(bytes) / double(1 << 20)) + " MiB";
}

}  // namespace

Expected<ImageRgb> render(const Scene& scene, const RayScene& rays, const GBuffer& g,
                          const RenderOptions& options, Stats& stats) {
  const SpwiOptions& o = options.spwi;
  const Plan plan = make_plan(scene, g, o);
  stats.plan = plan;
  stats.memory_bytes = plan.bytes();
  if (stats.memory_bytes > options.max_memory)
    return Error{"spwi's cascades need about " + mib(stats.memory_bytes) + ", more than the `" +
                 "max_memory` limit of " + mib(options.max_memory)};

  const Background bg(scene);
  // Later bounces: what the surfaces the rays meet reflect, from the probe grid's radiance cache
  // (seed 001 4.3 as a world-space cache), on top of what they emit.
  std::optional<grid::RadianceCache> cache;
  if (options.bounces > 1) {
    Stopwatch watch;
    Expected<grid::RadianceCache> built =
        grid::radiance_cache(scene, rays, options, options.bounces - 1);
    if (!built) return built.error();
    cache = std::move(*built);
    stats.memory_bytes += cache->bytes();
    stats.stages.push_back({"radiance cache", watch.ms()});
  }
  // What a ray along `dir` sees at its hit: the emission, and with a cache the reflected light
  // on the side the ray comes from.
  auto surface = [&](const Hit& hit, Vec3 dir) {
    Rgb l = emission_at(scene, hit);
    if (cache) {
      const Vec3 n =
          dot(hit.geometric_normal, dir) < 0 ? hit.geometric_normal : -hit.geometric_normal;
      l += cache->reflected(hit.position, n);
    }
    return l;
  };
  std::atomic<std::uint64_t> ray_count{0};
  std::vector<Rgb> upper, lower;
  std::vector<Probe> upper_probes;
  // Cascades from the top down (Alg. 9): each merges with the one above, then takes its place.
  for (int i = plan.cascades - 1; i >= 0; --i) {
    Stopwatch watch;
    const bool minmax = o.merge == SpwiMerge::minmax;
    std::vector<Probe> probes = minmax ? place_minmax_probes(scene, g, plan, i, o.depth_bias)
                                       : place_probes(scene, g, plan, i, o.depth_bias);
    std::vector<std::array<Probe, 4>> sub_probes;
    if (o.preaverage) sub_probes = place_sub_probes(scene, g, plan, i, o.depth_bias);
    const int side = plan.map_side(i), nx = plan.nx[std::size_t(i)];
    const std::uint64_t count = plan.probes(i);
    const std::vector<Vec3> dirs = octahedral::map_directions(side);
    lower.assign(std::size_t(plan.rays(i)), Rgb{});
    const bool top = i == plan.cascades - 1;
    // The top cascade's interval runs to infinity: its misses see the sky, whatever the reach
    // of its nominal interval (the cascade count stops at the screen's diagonal).
    const float a = plan.interval_start(i),
                b = top ? std::numeric_limits<float>::infinity() : plan.interval_end(i);
    const int up = i + 1;
    const int up_side = top ? 0 : plan.map_side(up);
    const std::uint64_t up_count = top ? 0 : plan.probes(up);
    // The upper radiance towards lower direction (u, v): the mean of its 2x2 children (4x4 with
    // branching 16) that hold light (the bilinear sample of the upper map at the lower cell's
    // centre, which crosses no seam; with 4x4, their box mean); false when none does.
    const int split = 1 << plan.step;
    auto upper_mean = [&](int probe, int u, int v, Rgb& mean) {
      Rgb sum{};
      int n = 0;
      for (int dv = 0; dv < split; ++dv)
        for (int du = 0; du < split; ++du) {
          const std::size_t d = std::size_t(split * v + dv) * up_side + std::size_t(split * u + du);
          const Rgb& c = upper[d * up_count + std::size_t(probe)];
          if (!holds_light(c)) continue;
          sum += c;
          ++n;
        }
      if (n == 0) return false;
      mean = sum * (1.0f / float(n));
      return true;
    };
    parallel_for(plan.ny[std::size_t(i)], [&](int py) {
      std::uint64_t local = 0;
      // A probe's rays as one stream, reused along the row.
      std::vector<Ray> batch;
      std::vector<Hit> batch_hits;
      std::vector<std::uint8_t> batch_found;
      std::vector<int> batch_cell;
      batch.reserve(std::size_t(side) * side);
      batch_cell.reserve(std::size_t(side) * side);
      for (int tile = py * nx, end = tile + nx; tile < end; ++tile)
        for (int layer = 0; layer < plan.layers; ++layer) {
          const int px = tile - py * nx;
          const std::size_t q = std::size_t(tile) * std::size_t(plan.layers) + std::size_t(layer);
          const Probe& pr = probes[q];
          if (!pr.valid) continue;
          Corners c;
          bool merge = !top;
          const double sx = probe_x(px, plan.spacing(i)), sy = probe_x(py, plan.spacing(i));
          if (merge && minmax) {
            c = minmax_corners(corners(sx, sy, plan.spacing(up), plan.nx[std::size_t(up)],
                                       plan.ny[std::size_t(up)]),
                               upper_probes, pr.depth);
            merge = normalise(c, upper_probes);
          } else if (merge) {
            c = valid_corners(sx, sy, plan.spacing(up), plan.nx[std::size_t(up)],
                              plan.ny[std::size_t(up)], upper_probes);
            // The fix weighs its 4 segments as the bilateral merge weighs probes: a probe across a
            // depth edge would send the segment through whatever lies between.
            if (o.merge == SpwiMerge::bilateral || o.merge == SpwiMerge::fix)
              bilateral(c, upper_probes, pr.depth, o.merge_edge);
            if (o.merge == SpwiMerge::bilinear3d) bilinear3d(c, upper_probes, pr.p);
            merge = normalise(c, upper_probes);
          }
          // This cascade's ray from probe `from` along d (from the probe with the overlap).
          auto interval_ray = [&](const Probe& from, Vec3 d) {
            return Ray{rays.spawn(from.p, from.n, d), d, o.overlap ? 0.0f : a, b};
          };
          // What the interval ray r (map cell (u, v)) brings, given its hit: the surface's
          // emission, or the merge with the cascade above.
          auto resolve = [&](const Ray& r, bool found, const Hit& hit, int u, int v) -> Rgb {
            if (found) return hit.t >= a ? surface(hit, r.direction) : kNoLight;  // opaque
            // The top cascade's misses see the sky; so do rays of a probe with no upper probe
            // around it (only sky above it on screen).
            if (!merge) return top_background(bg, r.direction, o.sun);
            Rgb sum{}, got;
            float weight = 0;
            for (int j = 0; j < c.n; ++j)
              if (c.w[std::size_t(j)] > 0 && upper_mean(c.index[std::size_t(j)], u, v, got)) {
                sum += got * c.w[std::size_t(j)];
                weight += c.w[std::size_t(j)];
              }
            if (weight > 0) return sum * (1 / weight);
            // No upper probe has light for this direction (its rays met surfaces before their
            // intervals, or the upper map has only directions into their surfaces): this ray
            // continues itself, to infinity as the top cascade does.
            ++local;
            Hit rest_hit;
            const Ray rest{r.origin, r.direction, b, std::numeric_limits<float>::infinity()};
            return rays.intersect(rest, rest_hit) ? surface(rest_hit, r.direction)
                                                  : top_background(bg, r.direction, o.sun);
          };
          // The radiance probe `from` receives along d from this cascade's interval and, through
          // the merge, from beyond it.
          auto ray_value = [&](const Probe& from, Vec3 d, int u, int v) -> Rgb {
            if (dot(d, from.n) <= 0) return kNoLight;  // into the probe's own surface
            Hit h;
            if (merge && o.merge == SpwiMerge::fix) {
              // A segment from this probe to the start of each upper probe's interval in this
              // direction, merged with that probe alone: the merged ray is continuous.
              Rgb sum{};
              float weight = 0;
              for (int j = 0; j < c.n; ++j) {
                if (c.w[std::size_t(j)] <= 0) continue;
                const Probe& uq = upper_probes[std::size_t(c.index[std::size_t(j)])];
                // From where this cascade's interval starts to where the upper one's starts.
                const Vec3 target = uq.p + d * b;
                const Vec3 start =
                    a > 0 ? from.p + d * a : rays.spawn(from.p, from.n, target - from.p);
                const Ray r{start, target - start, 0, 1};
                Rgb got;
                ++local;
                if (rays.intersect(r, h))
                  got = surface(h, r.direction);
                else if (!upper_mean(c.index[std::size_t(j)], u, v, got))
                  continue;
                sum += got * c.w[std::size_t(j)];
                weight += c.w[std::size_t(j)];
              }
              return weight > 0 ? sum * (1 / weight) : kNoLight;
            }
            const Ray r = interval_ray(from, d);
            ++local;
            return resolve(r, rays.intersect(r, h), h, u, v);
          };
          // With the fix, a segment above cascade 0 starts where the cascade below aimed: at this
          // probe's interval start, not a sub-probe's, so only cascade 0 is pre-averaged there.
          const bool pre = o.preaverage && !(merge && o.merge == SpwiMerge::fix && a > 0);
          const std::array<Probe, 4>* subs = pre ? &sub_probes[std::size_t(tile)] : nullptr;
          if (!subs && !(merge && o.merge == SpwiMerge::fix)) {
            // One stream of the probe's rays: from one point, through neighbouring map cells in
            // order, as the camera's rays are (Embree's coherent stream pays for those).
            batch.clear();
            batch_cell.clear();
            for (int k = 0; k < side * side; ++k) {
              if (dot(dirs[std::size_t(k)], pr.n) <= 0) {
                lower[std::size_t(k) * count + q] = kNoLight;  // into the probe's own surface
                continue;
              }
              batch.push_back(interval_ray(pr, dirs[std::size_t(k)]));
              batch_cell.push_back(k);
            }
            batch_hits.resize(batch.size());
            batch_found.resize(batch.size());
            rays.intersect(batch, batch_hits, batch_found, true);
            local += batch.size();
            for (std::size_t j = 0; j < batch.size(); ++j) {
              const int k = batch_cell[j];
              lower[std::size_t(k) * count + q] =
                  resolve(batch[j], batch_found[j] != 0, batch_hits[j], k % side, k / side);
            }
            continue;
          }
          for (int v = 0; v < side; ++v)
            for (int u = 0; u < side; ++u) {
              const std::size_t k = std::size_t(v) * side + u;
              const Vec3 d = dirs[k];
              Rgb& out = lower[k * count + q];
              if (!subs) {
                out = ray_value(pr, d, u, v);
                continue;
              }
              // Pre-averaging (seed 000 section 5.1): the same direction traced from the 2x2
              // sub-probes of the tile, averaged into the probe (4x the rays, the same storage).
              Rgb sum{};
              int n = 0;
              for (const Probe& sp : *subs) {
                if (!sp.valid) continue;
                const Rgb got = ray_value(sp, d, u, v);
                if (!holds_light(got)) continue;
                sum += got;
                ++n;
              }
              out = n > 0 ? sum * (1.0f / float(n)) : kNoLight;
            }
        }
      ray_count.fetch_add(local, std::memory_order_relaxed);
    });
    std::swap(upper, lower);
    upper_probes = std::move(probes);
    stats.stages.push_back({"cascade " + std::to_string(i), watch.ms()});
  }

  // Final gather (Alg. 11): the 4 nearest cascade-0 probes, depth-aware weights, each probe's
  // cosine-weighted mean radiance over the pixel's hemisphere.
  Stopwatch watch;
  const int side = plan.map_side(0);
  const std::vector<Vec3> dirs = octahedral::map_directions(side);
  const std::uint64_t count = plan.probes(0);
  // The sun by one shadow ray per pixel, unless the top cascade carries it.
  const SunLight sun(scene, rays);
  const bool sun_direct = o.sun == SpwiSun::direct;
  // --gather probe: each probe's cosine-weighted mean radiance about its own normal, once, so
  // that a pixel reads 4 values instead of 4 x Q0 (exact where the pixel's normal is its
  // probes', as on flat surfaces). kNoLight where the probe has none towards its hemisphere.
  std::vector<Rgb> probe_mean;
  if (o.gather == SpwiGather::probe) {
    probe_mean.assign(count, kNoLight);
    parallel_for(int(count), [&](int k) {
      const Probe& pr = upper_probes[std::size_t(k)];
      if (!pr.valid) return;
      cosine_mean(
          dirs, pr.n,
          [&](std::size_t d) -> const Rgb& { return upper[d * count + std::size_t(k)]; },
          probe_mean[std::size_t(k)]);
    });
  }
  // A probe's cosine-weighted mean radiance over the hemisphere of normal n (--gather pixel) or
  // its own (--gather probe); false where it has no light there.
  auto probe_radiance = [&](int index, Vec3 n, Rgb& mean) {
    if (!probe_mean.empty()) {
      mean = probe_mean[std::size_t(index)];
      return holds_light(mean);
    }
    return cosine_mean(
        dirs, n, [&](std::size_t d) -> const Rgb& { return upper[d * count + std::size_t(index)]; },
        mean);
  };
  stats.rays = ray_count.load();
  ImageRgb img = shade_pixels(
      g, bg, stats.rays, [&](int x, int y, std::size_t k, const Hit& h, std::uint64_t& local) {
        const Vec3 n = h.shading_normal;
        Rgb l = emission_at(scene, h);
        const Rgb albedo = albedo_at(scene, h);
        const float depth = g.linear_depth(k);
        Corners c;
        if (o.merge == SpwiMerge::minmax) {
          c = minmax_corners(corners(x + 0.5, y + 0.5, plan.spacing(0), plan.nx[0], plan.ny[0]),
                             upper_probes, depth);
        } else {
          c = valid_corners(x + 0.5, y + 0.5, plan.spacing(0), plan.nx[0], plan.ny[0],
                            upper_probes);
          bilateral(c, upper_probes, depth, o.gather_edge);
        }
        if (o.gather_normal > 0) {
          // Probes on surfaces facing elsewhere (the front of a block, for a pixel on its top)
          // gather light the pixel does not see: weighted by cos^p of the normals' angle, unless
          // that leaves no probe.
          Corners facing = c;
          float left = 0;
          for (int j = 0; j < c.n; ++j) {
            const Vec3 pn = upper_probes[std::size_t(c.index[std::size_t(j)])].n;
            facing.w[std::size_t(j)] *=
                std::pow(std::max(0.0f, dot(pn, h.geometric_normal)), o.gather_normal);
            left += facing.w[std::size_t(j)];
          }
          if (left > 0) c = facing;
        }
        if (normalise(c, upper_probes)) {
          Rgb e{};
          float used = 0;  // the weight of probes with light towards this pixel's hemisphere
          for (int j = 0; j < c.n; ++j) {
            Rgb mean;
            if (c.w[std::size_t(j)] <= 0 || !probe_radiance(c.index[std::size_t(j)], n, mean))
              continue;
            e += mean * c.w[std::size_t(j)];
            used += c.w[std::size_t(j)];
          }
          if (used > 0) l += albedo * e * (1 / used);
        }
        if (sun_direct) l += sun.reflected(h, albedo, local);
        return l;
      });
  stats.stages.push_back({"gather", watch.ms()});
  return img;
}

}  // namespace penumbra::spaceland::spwi
