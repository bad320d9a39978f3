#include "spaceland/spwi/spwi.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/math.hpp"
#include "core/octahedral.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/brdf.hpp"
#include "spaceland/brdf_albedo.hpp"
#include "spaceland/cascade/cone.hpp"
#include "spaceland/cascade/radiance.hpp"
#include "spaceland/cascade/sphere_lights.hpp"
#include "spaceland/color.hpp"
#include "spaceland/radiance_cache.hpp"
#include "spaceland/shade.hpp"
#include "spaceland/sky.hpp"
#include "spaceland/spwi/probes.hpp"
#include "spaceland/sun.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland::spwi {

using cascade::cone_cascade;
using cascade::holds_light;
using cascade::kNoLight;
using cascade::lobe_cells;
using cascade::lobe_mean;
using cascade::LobeCells;
using cascade::RadianceStore;

namespace {

// The most cascades worth having on a w x h image: until the probe spacing reaches the image's
// diagonal (one probe for the whole screen). Past it a cascade only multiplies its directions.
int screen_cascades(const Layout& l) {
  const double diagonal = std::sqrt(double(l.width) * l.width + double(l.height) * l.height);
  return cascade::count_until(cascade::kMaxCascades / l.levels.spacing_step,
                              [&](int i) { return double(l.spacing(i)) < diagonal; });
}

}  // namespace

int probe_spacing_for(const SpwiOptions& o, int width, int height) {
  if (o.probe_spacing > 0) return o.probe_spacing;
  // A small image's probes at 4 pixels are too few for its lights' pools and shadows. Measured
  // (2026-11-27): the scene family at 160 x 120, median and worst error, s0 4 30% and 88%, 2 22%
  // and 65%, 1 20% and 56% (1x, 2x, 4-8x the time); but s0 1 is worse on exact scenes at 96 x 72
  // (a sphere light over a plane: 15% against 8.5% at 4; the light falls to coarser cascades as
  // t0, four probe spacings, shrinks), where 2 is the best of the three (a radius-0.3 light over
  // a wide floor: 7.1%, 4.3%, 6.3%).
  return std::min(width, height) / kSpwiSpacing < kSpwiProbesAcross ? kSpwiSpacing / 2
                                                                    : kSpwiSpacing;
}

namespace {

// What the options fix of a layout for a w x h image (no t0, no cascade count, no grids yet).
// Branching B = 4^step: probe spacing and map side x 2^step, intervals x B per cascade (Alg. 6).
Layout options_layout(int width, int height, const SpwiOptions& o) {
  Layout l;
  l.width = width;
  l.height = height;
  const int step = o.branching == 16 ? 2 : 1;
  l.levels.spacing0 = probe_spacing_for(o, width, height);
  l.levels.side0 = std::max(1, int(std::lround(std::sqrt(double(std::max(1, o.directions))))));
  l.levels.spacing_step = step;
  l.levels.side_step = step;
  l.levels.interval_step = 2 * step;
  l.preaverage = o.preaverage;
  l.layers = o.merge == SpwiMerge::minmax ? 2 : 1;
  return l;
}

// The tiles of each of the layout's cascades.
void add_grids(Layout& l) {
  for (int i = 0; i < l.count(); ++i) {
    l.nx.push_back((l.width + l.spacing(i) - 1) / l.spacing(i));
    l.ny.push_back((l.height + l.spacing(i) - 1) / l.spacing(i));
  }
}

}  // namespace

int cone_top(const Scene& scene, const cascade::Levels& l, const SpwiOptions& o) {
  return o.specular == SpecularQuery::cone ? cascade::cone_top(l, cascade::narrowest_lobe(scene))
                                           : 0;
}

std::uint64_t cone_bytes(const Layout& l, int top) {
  std::uint64_t bytes = 0;
  for (int i = 0; top > 0 && i <= top; ++i) {
    if (i < top) bytes += l.rays(i) * sizeof(Interval);
    if (i > 0)
      bytes += l.rays(i) * sizeof(Rgb) + l.probes(i) * sizeof(Probe) +
               l.levels.directions(i) * sizeof(Vec3);
  }
  return bytes;
}

std::uint64_t Layout::bytes() const {
  std::uint64_t largest = 0, probe_bytes = 0;
  for (int i = 0; i < count(); ++i) {
    largest = std::max(largest, rays(i));
    probe_bytes += probes(i) * sizeof(Probe) * (preaverage ? 5 : 1);
  }
  // Plus cascade 0's per-probe means (--gather probe), counted either way: 12 B a probe.
  return 2 * largest * sizeof(Rgb) + probe_bytes + (count() > 0 ? probes(0) * sizeof(Rgb) : 0);
}

std::uint64_t bytes_upper_bound(const Scene& scene, const SpwiOptions& o) {
  Layout l = options_layout(scene.camera.width, scene.camera.height, o);
  l.levels.count = o.cascades > 0 ? std::min(o.cascades, cascade::kMaxCascades / l.levels.side_step)
                                  : screen_cascades(l);
  add_grids(l);
  return l.bytes() + cone_bytes(l, cone_top(scene, l.levels, o));
}

Status check_options(const SpwiOptions& o) {
  if (o.probe_spacing < 0 || o.probe_spacing > 64)
    return Error{"`spwi.probe_spacing`: expected 1..64 (0: derived), found " +
                 std::to_string(o.probe_spacing)};
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
  const int most = o.branching == 16 ? cascade::kMaxCascades / 2 : cascade::kMaxCascades;
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
  if (o.specular != SpecularQuery::cone && o.specular != SpecularQuery::wide &&
      o.specular != SpecularQuery::ray)
    return Error{"`spwi.specular`: expected cone, wide or ray"};
  if (!(o.gather_normal >= 0 && o.gather_normal <= 64))
    return Error{"`spwi.gather_normal`: expected an exponent in [0, 64], found " +
                 io::format_number(o.gather_normal)};
  return {};
}

Status check_scene(const Scene& scene) {
  return refuse_fog(scene, "spwi", "--method pt");
}

namespace {

// Four times the world size of s0 pixels at the median depth of the visible surfaces. One probe
// spacing (the penumbra condition's balance at the median depth) was measured too short: probes
// on farther surfaces are further apart, and small lights need cascade 0's finer directions to
// reach them. 4x is the best or near it on 8 of 9 scenes (docs/QUALITY.md, "SPWI against the
// path tracer: the study").
float derived_t0(const Scene& scene, const GBuffer& g, int probe_spacing) {
  std::vector<float> depths;
  for (std::size_t k = 0; k < g.hits.size(); ++k)
    if (g.found[k]) depths.push_back(g.linear_depth(k));
  float median = 1;
  if (!depths.empty()) {
    std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
    median = depths[depths.size() / 2];
  }
  const double pixel = 2 * median * std::tan(double(scene.camera.fov_y) * kPi / 360) / g.height;
  return float(std::max(1e-6, 4 * pixel * probe_spacing));
}

}  // namespace

Layout make_layout(const Scene& scene, const GBuffer& g, const SpwiOptions& o) {
  Layout l = options_layout(g.width, g.height, o);
  l.levels.t0 = o.interval > 0 ? o.interval : derived_t0(scene, g, l.levels.spacing0);
  l.levels.count = o.cascades;
  if (l.levels.count == 0) {
    // Enough that the last interval reaches across the scene's bounds and the camera.
    Bounds b = scene_bounds(scene);
    b.lo = min(b.lo, scene.camera.position);
    b.hi = max(b.hi, scene.camera.position);
    l.levels.count = cascade::count_to_reach(l.levels, length(b.hi - b.lo), screen_cascades(l));
  }
  add_grids(l);
  return l;
}

void shift_lattice(Layout& layout, std::uint64_t frame) {
  const int s = layout.spacing(0);
  // Frame 0's point (0, 0) is moved to the tile's middle, where the unshifted probe sits.
  const auto shift = [s](double u) {
    const double v = u + 0.5;
    return int(std::floor((v - std::floor(v)) * s)) - s / 2;
  };
  layout.shift_x = shift(temporal::radical_inverse(frame, 2));
  layout.shift_y = shift(temporal::radical_inverse(frame, 3));
}

namespace {

// What a ray along `dir` sees at a surface hit: the emission, and with a cache the light
// reflected on the side the ray comes from.
struct Surfaces {
  const Scene& scene;
  const RadianceCache* cache;
  Rgb operator()(const Hit& hit, Vec3 dir) const {
    Rgb l = emission_at(scene, hit);
    if (cache) {
      const Vec3 n =
          dot(hit.geometric_normal, dir) < 0 ? hit.geometric_normal : -hit.geometric_normal;
      l += cache->reflected(hit.position, n);
    }
    return l;
  }
};

// SPWI's tracer for the cascade core: exact Embree rays; what leaves the scene sees the sky, with
// the sun's disk when the cascades carry the sun.
struct EmbreeTracer {
  const RayScene& rays;
  const Surfaces& surface;
  const Background& bg;
  SpwiSun sun;
  std::uint64_t& count;
  cascade::Segment trace(Vec3 origin, Vec3 dir, float t0, float t1) {
    ++count;
    Hit h;
    if (!rays.intersect(Ray{origin, dir, t0, t1}, h)) return {};
    return {surface(h, dir), {}, h.t, true};
  }
  Rgb sky(Vec3 d) const { return sun == SpwiSun::cascades ? bg(d) : bg.sky(d); }
};

// One cascade of the hierarchy, traced and merged with the one above (Alg. 9): its probes, what
// it traces and the stores it reads and fills.
struct ScreenCascade {
  const SolveContext& ctx;
  const SpwiOptions& o;
  const Layout& layout;
  const Surfaces& surface;
  const Background& bg;
  int i;
  const std::vector<Probe>& probes;
  const std::vector<std::array<Probe, 4>>& sub_probes;
  const std::vector<Probe>& upper_probes;
  const RadianceStore& upper;
  RadianceStore& lower;
  const cascade::SphereLights& lights;
  // With sphere lights: where each ray of the cascade above stopped (read) and of this one
  // (written), probe-major as the stores (-1: no ray, into the probe's surface; infinity: it met
  // no surface).
  const std::vector<float>& upper_reach;
  std::vector<float>& lower_reach;
  // Where the cone query keeps this cascade's own intervals (null: it does not), probe-major.
  std::vector<Interval>* own;
  std::vector<Vec3> dirs = cascade::direction_map(layout.levels, i);
  // The final gather's cells, that the lights' shares are made exact for.
  std::vector<Vec3> dirs0 = cascade::direction_map(layout.levels, 0);
  // The top cascade's interval runs to infinity: its misses see the sky, whatever the reach of
  // its nominal interval (the cascade count stops at the screen's diagonal).
  float a = layout.levels.interval_start(i), b = layout.levels.interval_end(i);
  bool top = layout.levels.top(i);
  int split = layout.levels.split();

  // Per row of tiles: the probe being traced, the upper probes it merges with, its ray stream,
  // and where each of its cells' rays stopped (per sub-probe; -1: no ray, into its surface).
  struct Row {
    std::uint64_t rays = 0;
    Corners c;
    bool merge = false;
    std::vector<Ray> batch;
    std::vector<Hit> hits;
    std::vector<std::uint8_t> found;
    std::vector<int> cell;
    std::vector<std::array<float, 4>> reach;
    std::vector<Rgb> before;  // a probe's map before its lights' shares (for its own intervals)
  };

  // Probe p's share of the sphere lights, in the cells whose rays reach them (the fraction of a
  // pre-averaged cell's sub-probe rays that do).
  void add_lights(Row& row, const Probe& p, Rgb* out, Interval* mine) const {
    if (lights.empty()) return;
    const std::size_t cells = std::size_t(layout.map_side(i)) * layout.map_side(i);
    if (mine) row.before.assign(out, out + cells);
    const cascade::Uppers up = cascade::uppers_of(
        row.c, b, [&](std::size_t j) { return upper_probes[std::size_t(row.c.index[j])].p; });
    auto seen = [&](std::size_t k, float d) {
      int with_light = 0, past = 0;
      for (float r : row.reach[k])  // a ray stopped before the interval holds no light
        if (r >= a) ++with_light, past += r >= d;
      return with_light > 0 ? float(past) / float(with_light) : 0.0f;
    };
    const std::size_t up_cells =
        top ? 0 : std::size_t(layout.map_side(i + 1)) * layout.map_side(i + 1);
    auto past = [&](const cascade::SphereLight& l) {
      if (!row.merge) return 1.0f;  // only sky above: nothing beyond to stop it
      return cascade::upper_clear(up, layout.map_side(i + 1), l, [&](std::size_t j, std::size_t k) {
        return upper_reach[std::size_t(row.c.index[j]) * up_cells + k];
      });
    };
    const cascade::GatherCells gather{&dirs0, layout.map_side(0)};
    lights.add(p.p, p.n, a, b, row.merge ? &up : nullptr, layout.map_side(i), out, seen, past,
               &gather);
    // The shares are light inside this cascade's interval: its own.
    if (mine)
      for (std::size_t k = 0; k < cells; ++k)
        if (holds_light(row.before[k]) && holds_light(mine[k].radiance))
          mine[k].radiance += out[k] - row.before[k];
  }

  EmbreeTracer tracer(Row& row) const { return {ctx.rays, surface, bg, o.sun, row.rays}; }

  // This cascade's ray from probe `from` along d (from the probe with the overlap).
  Ray interval_ray(const Probe& from, Vec3 d) const {
    return Ray{ctx.rays.spawn(from.p, from.n, d), d, o.overlap ? 0.0f : a, b};
  }

  // A ray from probe p that hit a sphere light small for this cascade's cells goes on past it
  // (add_lights spreads its light instead); false where it then hits nothing.
  bool pass_small_lights(Vec3 p, Ray r, bool found, Hit& h) const {
    if (lights.empty()) return found;
    for (int n = 0; found && n < 8; ++n) {
      const float exit = lights.pass(ctx.scene, h, p, r.origin, r.direction);
      if (exit < 0) break;
      r.tmin = exit;
      found = ctx.rays.intersect(r, h);
    }
    return found;
  }

  // What the interval ray r (map cell (u, v)) brings, given its hit: the surface's emission, or
  // the merge with the cascade above. `reach` (with sphere lights) becomes where a ray that met
  // nothing in its interval stopped beyond it: its merged continuation's stop
  // (cascade::merged_reach), or its own trace's where it goes on by itself.
  // `mine`: its own interval's part (what goes on to the merge counts as passing through).
  Rgb resolve(Row& row, const Ray& r, bool found, const Hit& hit, int u, int v, float& reach,
              Interval& mine) const {
    if (found) {  // opaque
      mine = {hit.t >= a ? surface(hit, r.direction) : kNoLight, 0};
      return mine.radiance;
    }
    // The top cascade's misses see the sky; so do rays of a probe with no upper probe around it
    // (only sky above it on screen).
    EmbreeTracer t = tracer(row);
    if (!row.merge) {
      mine = {t.sky(r.direction), 0};
      return mine.radiance;
    }
    Rgb merged;
    if (cascade::merge_children(upper, row.c, u, v, split, merged)) {
      if (!lights.empty())
        reach = cascade::merged_reach(row.c, u, v, split, upper_reach.data(),
                                      layout.map_side(i + 1), b);
      mine = {Rgb{}, 1};
      return merged;
    }
    // No upper probe has light for this direction (its rays met surfaces before their intervals,
    // or the upper map has only directions into their surfaces): the ray goes on by itself.
    mine = {cascade::continue_to_sky(t, r.origin, r.direction, b, &reach), 0};
    return mine.radiance;
  }

  // The bilinear fix: a segment from this probe to the start of each upper probe's interval in
  // this direction, merged with that probe alone, so that the merged ray is continuous.
  // `reach`: the nearest surface its segments met, from the probe (infinity: none).
  Rgb fixed_ray(Row& row, const Probe& from, Vec3 d, int u, int v, float& reach,
                Interval& mine) const {
    Rgb sum{}, own{};
    float weight = 0, through = 0;
    for (int j = 0; j < row.c.n; ++j) {
      if (row.c.w[std::size_t(j)] <= 0) continue;
      const std::uint64_t uq = row.c.index[std::size_t(j)];
      // From where this cascade's interval starts to where the upper one's starts.
      const Vec3 target = upper_probes[std::size_t(uq)].p + d * b;
      const Vec3 start = a > 0 ? from.p + d * a : ctx.rays.spawn(from.p, from.n, target - from.p);
      const float len = length(target - start);
      if (!(len > 0)) continue;
      const Ray r{start, (target - start) * (1 / len), 0, len};
      Rgb got;
      Hit h;
      ++row.rays;
      const float w = row.c.w[std::size_t(j)];
      if (pass_small_lights(from.p, r, ctx.rays.intersect(r, h), h)) {
        got = surface(h, r.direction);
        reach = std::min(reach, length(h.position - from.p));
        own += got * w;
      } else if (cascade::children_mean(upper, uq, u, v, split, got)) {
        through += w;
      } else {
        continue;
      }
      sum += got * w;
      weight += w;
    }
    if (!(weight > 0)) return kNoLight;
    mine = {own * (1 / weight), through / weight};
    return sum * (1 / weight);
  }

  // The radiance probe `from` receives along d from this cascade's interval and, through the
  // merge, from beyond it; `reach` is where its ray stopped (infinity: at no surface).
  Rgb ray_value(Row& row, const Probe& from, Vec3 d, int u, int v, float& reach,
                Interval& mine) const {
    reach = -1;  // no ray
    mine = {};
    if (dot(d, from.n) <= 0) return kNoLight;  // into the probe's own surface
    reach = cascade::kInfinity;
    if (row.merge && o.merge == SpwiMerge::fix) {
      const Rgb got = fixed_ray(row, from, d, u, v, reach, mine);
      // Its segments start at the interval: with sphere lights to see past it, the stretch
      // before is traced too (a wall there would otherwise let them through).
      if (!lights.empty() && a > 0) {
        const Ray before{ctx.rays.spawn(from.p, from.n, d), d, 0, a};
        Hit h;
        ++row.rays;
        if (pass_small_lights(from.p, before, ctx.rays.intersect(before, h), h))
          reach = std::min(reach, h.t);
      }
      return got;
    }
    const Ray r = interval_ray(from, d);
    Hit h;
    ++row.rays;
    const bool found = pass_small_lights(from.p, r, ctx.rays.intersect(r, h), h);
    if (found) reach = h.t;
    return resolve(row, r, found, h, u, v, reach, mine);
  }

  // One stream of the probe's rays: from one point, through neighbouring map cells in order, as
  // the camera's rays are (Embree's coherent stream pays for those).
  void trace_stream(Row& row, const Probe& pr, Rgb* out, Interval* mine) const {
    const int side = layout.map_side(i);
    row.batch.clear();
    row.cell.clear();
    for (int k = 0; k < side * side; ++k) {
      if (dot(dirs[std::size_t(k)], pr.n) <= 0) {
        out[k] = kNoLight;  // into the probe's own surface
        continue;
      }
      row.batch.push_back(interval_ray(pr, dirs[std::size_t(k)]));
      row.cell.push_back(k);
    }
    row.hits.resize(row.batch.size());
    row.found.resize(row.batch.size());
    ctx.rays.intersect(row.batch, row.hits, row.found, true);
    row.rays += row.batch.size();
    if (!lights.empty()) row.reach.assign(std::size_t(side) * side, {-1, -1, -1, -1});
    for (std::size_t j = 0; j < row.batch.size(); ++j) {
      const int k = row.cell[j];
      row.found[j] = pass_small_lights(pr.p, row.batch[j], row.found[j] != 0, row.hits[j]);
      float reach = row.found[j] ? row.hits[j].t : cascade::kInfinity;
      Interval own;
      out[k] = resolve(row, row.batch[j], row.found[j] != 0, row.hits[j], k % side, k / side, reach,
                       own);
      if (mine) mine[k] = own;
      if (!lights.empty()) row.reach[std::size_t(k)][0] = reach;
    }
    add_lights(row, pr, out, mine);
  }

  // Pre-averaging (seed 000 section 5.1): each direction traced from the 2x2 sub-probes of the
  // tile, averaged into the probe (4x the rays, the same storage); otherwise ray by ray.
  void trace_each(Row& row, const Probe& pr, const std::array<Probe, 4>* subs, Rgb* out,
                  Interval* mine) const {
    const int side = layout.map_side(i);
    if (!lights.empty()) row.reach.assign(std::size_t(side) * side, {-1, -1, -1, -1});
    for (int v = 0; v < side; ++v)
      for (int u = 0; u < side; ++u) {
        const std::size_t k = std::size_t(v) * side + u;
        const Vec3 d = dirs[k];
        std::array<float, 4> reach{-1, -1, -1, -1};
        Interval own;
        if (!subs) {
          out[k] = ray_value(row, pr, d, u, v, reach[0], own);
        } else {
          std::array<Rgb, 4> got;
          std::array<Interval, 4> owns;
          int n = 0;
          for (const Probe& sp : *subs) {
            if (!sp.valid) continue;
            got[std::size_t(n)] =
                ray_value(row, sp, d, u, v, reach[std::size_t(n)], owns[std::size_t(n)]);
            ++n;
          }
          out[k] = cascade::mean_with_light(std::span<const Rgb>(got.data(), std::size_t(n)));
          // The sub-probes' own intervals averaged as their values are.
          own = {};
          Rgb sum{};
          float through = 0;
          int with = 0;
          for (int s = 0; s < n; ++s)
            if (holds_light(owns[std::size_t(s)].radiance)) {
              sum += owns[std::size_t(s)].radiance;
              through += owns[std::size_t(s)].through;
              ++with;
            }
          if (with > 0) own = {sum * (1.0f / float(with)), through / float(with)};
        }
        if (mine) mine[k] = own;
        if (!lights.empty()) row.reach[k] = reach;
      }
    add_lights(row, pr, out, mine);
  }

  void trace_probe(Row& row, int px, int py, std::uint64_t q) const {
    const Probe& pr = probes[std::size_t(q)];
    if (!pr.valid) return;
    row.merge =
        !top && upper_corners(layout, i + 1, tile_centre(px, layout.spacing(i)) + layout.shift_x,
                              tile_centre(py, layout.spacing(i)) + layout.shift_y, pr, upper_probes,
                              o, row.c);
    const bool fix = row.merge && o.merge == SpwiMerge::fix;
    // With the fix, a segment above cascade 0 starts where the cascade below aimed: at this
    // probe's interval start, not a sub-probe's, so only cascade 0 is pre-averaged there.
    const bool pre = o.preaverage && !(fix && a > 0);
    const std::array<Probe, 4>* subs =
        pre ? &sub_probes[std::size_t(q) / std::size_t(layout.layers)] : nullptr;
    Interval* mine = own ? own->data() + std::size_t(q) * layout.levels.directions(i) : nullptr;
    if (!subs && !fix)
      trace_stream(row, pr, lower.probe(q), mine);
    else
      trace_each(row, pr, subs, lower.probe(q), mine);
    if (lights.empty()) return;
    // Where its rays stopped, for the cascade below's lights past its rays (the farthest of a
    // pre-averaged cell's sub-probe rays).
    const std::size_t cells = row.reach.size();
    for (std::size_t k = 0; k < cells; ++k) {
      const std::array<float, 4>& r = row.reach[k];
      lower_reach[std::size_t(q) * cells + k] = std::max({r[0], r[1], r[2], r[3]});
    }
  }

  // Traces every probe, rows of tiles in parallel; returns the rays traced.
  std::uint64_t run() const {
    std::atomic<std::uint64_t> count{0};
    const int nx = layout.nx[std::size_t(i)];
    parallel_for(layout.ny[std::size_t(i)], [&](int py) {
      Row row;
      // A probe's rays as one stream, reused along the row.
      const std::size_t side = std::size_t(layout.map_side(i));
      row.batch.reserve(side * side);
      row.cell.reserve(side * side);
      for (int px = 0; px < nx; ++px)
        for (int layer = 0; layer < layout.layers; ++layer)
          trace_probe(
              row, px, py,
              (std::uint64_t(py) * nx + px) * std::uint64_t(layout.layers) + std::uint64_t(layer));
      count.fetch_add(row.rays, std::memory_order_relaxed);
    });
    return count.load();
  }
};

// What the cone query reads of cascade i (seed 001 2.6): its probes and directions, its merged
// radiance M_i (above cascade 0, whose store the gather has) and its own intervals U_i, T_i
// (below the top K).
struct KeptCascade {
  std::vector<Probe> probes;
  std::vector<Vec3> dirs;
  RadianceStore merged;
  std::vector<Interval> intervals;
};

// The final gather (Alg. 11): the 4 nearest cascade-0 probes, depth-aware weights, each probe's
// cosine-weighted mean radiance over the pixel's hemisphere; the sun by one shadow ray per pixel
// unless the top cascade carries it. Glossy pixels add their specular lobe (o.specular), the cone
// query reading `kept`. With ctx.want_exact, `exact` gets each pixel's emission and direct sun
// light and its diffuse albedo (temporal accumulation's SolveReport::exact).
ImageRgb gather(const SolveContext& ctx, const SpwiOptions& o, const Layout& layout,
                const RadianceStore& store, const std::vector<Probe>& probes, const Background& bg,
                const Surfaces& surface, const std::vector<KeptCascade>& kept, std::uint64_t& rays,
                temporal::Exact& exact) {
  const std::vector<Vec3> dirs = cascade::direction_map(layout.levels, 0);
  const std::uint64_t count = layout.probes(0);
  const SunLight sun(ctx.scene, ctx.rays, ctx.sun_rays);
  const bool sun_direct = o.sun == SpwiSun::direct;
  // --gather probe: each probe's cosine-weighted mean radiance about its own normal, once, so
  // that a pixel reads 4 values instead of 4 x Q0 (exact where the pixel's normal is its
  // probes', as on flat surfaces). kNoLight where the probe has none towards its hemisphere.
  std::vector<Rgb> probe_mean;
  if (o.gather == SpwiGather::probe) {
    probe_mean.assign(count, kNoLight);
    parallel_for(int(count), [&](int k) {
      const Probe& pr = probes[std::size_t(k)];
      if (pr.valid)
        cascade::cosine_mean(dirs, pr.n, store, std::uint64_t(k), probe_mean[std::size_t(k)]);
    });
  }
  // A probe's cosine-weighted mean radiance over the hemisphere of normal n (--gather pixel) or
  // its own (--gather probe); false where it has no light there.
  auto probe_radiance = [&](std::uint64_t index, Vec3 n, Rgb& mean) {
    if (probe_mean.empty()) return cascade::cosine_mean(dirs, n, store, index, mean);
    mean = probe_mean[std::size_t(index)];
    return holds_light(mean);
  };
  std::vector<float> cell_alphas;
  for (int i = 0; i < std::max(1, int(kept.size())); ++i)
    cell_alphas.push_back(cell_alpha(layout.map_side(i)));
  // The cone query (seed 001 2.6) of a lobe of width alpha at pixel (x, y), to cascade K:
  // U_0 + T_0 (U_1 + T_1 (... + T_{K-1} M_K)), each cascade read from its probes about the pixel
  // over the lobe no narrower than its cells; K = 0 is the widest query, merged cascade 0 alone.
  // Where cascade K's probes about the pixel have no light that way (none on its surface: a curved
  // one's normals turn away between them), the merged cascade below takes its place. False where
  // none has.
  auto cone = [&](int x, int y, std::size_t k, const Hit& h, Vec3 wo, float alpha, int top,
                  Rgb& out) {
    thread_local LobeCells cells;
    const Vec3 n = h.shading_normal;
    const Vec3 r = reflect(wo, n);
    Rgb acc{};
    bool merged = false;  // acc holds the merged cascade's answer
    for (int i = top; i >= 0; --i) {
      // Cascade 0 is the gather's (kept holds nothing of it without a cone above it).
      const KeptCascade* kc = i > 0 ? &kept[std::size_t(i)] : nullptr;
      Corners c;
      if (!gather_corners(layout, i, x, y, ctx.g.linear_depth(k), h.geometric_normal,
                          kc ? kc->probes : probes, o, c))
        continue;  // no probe of this cascade here: the rest is as above
      const float cell = cell_alphas[std::size_t(i)], a = std::max(alpha, cell);
      const int side = layout.map_side(i);
      lobe_cells(kc ? kc->dirs : dirs, side, a, n, wo, r, cascade::lobe_radius(i, side, a, cell),
                 cells);
      if (!merged) {
        const RadianceStore& m = kc ? kc->merged : store;
        Rgb sum{}, mean;
        float used = 0;
        for (int j = 0; j < c.n; ++j) {
          const Rgb* probe = m.probe(c.index[std::size_t(j)]);
          const float w = c.w[std::size_t(j)];
          if (w > 0 && lobe_mean(
                           cells, [&](std::uint32_t d) { return holds_light(probe[d]); },
                           [&](std::uint32_t d) { return probe[d]; }, mean)) {
            sum += mean * w;
            used += w;
          }
        }
        if (!(used > 0)) continue;
        acc = sum * (1 / used);
        merged = true;
        continue;
      }
      Rgb own{};
      float through = 0, used = 0;
      for (int j = 0; j < c.n; ++j) {
        const Interval* probe = kept[std::size_t(i)].intervals.data() +
                                std::size_t(c.index[std::size_t(j)]) * layout.levels.directions(i);
        const float w = c.w[std::size_t(j)];
        if (!(w > 0)) continue;
        // The probe's U and T over the lobe, in one pass.
        Rgb u{};
        float t = 0, weight = 0;
        for (const auto& [d, lw] : cells) {
          const Interval& in = probe[d];
          if (!holds_light(in.radiance)) continue;
          u += in.radiance * lw;
          t += in.through * lw;
          weight += lw;
        }
        if (!(weight > 0)) continue;
        own += u * (w / weight);
        through += t * (w / weight);
        used += w;
      }
      if (used > 0) acc = own * (1 / used) + acc * (through / used);
    }
    out = acc;
    return merged;
  };
  const int top = std::max(0, int(kept.size()) - 1);
  if (ctx.want_exact) {
    const std::size_t pixels = std::size_t(ctx.g.width) * ctx.g.height;
    exact.light.assign(pixels, Rgb{});
    exact.albedo.assign(pixels, Rgb{});
  }
  return shade_pixels(
      ctx.g, bg, rays, [&](int x, int y, std::size_t k, const Hit& h, std::uint64_t& local) {
        const Rgb emitted = emission_at(ctx.scene, h);
        Rgb l = emitted;
        const Brdf brdf = brdf_at(ctx.scene, h);
        const Vec3 wo = normalize(-ctx.g.directions[k]);
        const Vec3 n = h.shading_normal;
        // The Lambertian: its albedo and no specular lobe.
        const LobeAlbedo lobes = lobe_albedo(brdf, std::max(dot(n, wo), 0.0f));
        // The specular lobe, added after the diffuse.
        Rgb specular{};
        if (!brdf.lambertian && o.specular == SpecularQuery::ray) {
          // The baseline: one exact ray along the mirror direction.
          const Vec3 r = reflect(wo, n);
          Hit seen;
          ++local;
          const Ray ray{ctx.rays.spawn(h.position, h.geometric_normal, r), r, 0,
                        cascade::kInfinity};
          specular = lobes.specular * (ctx.rays.intersect(ray, seen) ? surface(seen, r)
                                       : o.sun == SpwiSun::cascades  ? bg(r)
                                                                     : bg.sky(r));
        } else if (!brdf.lambertian) {
          const float alpha = brdf.mirror() ? 0.0f : brdf.alpha;
          Rgb got;
          if (cone(x, y, k, h, wo, alpha, cone_cascade(layout.levels, alpha, top), got))
            specular = lobes.specular * got;
        }
        Corners c;
        if (gather_corners(layout, 0, x, y, ctx.g.linear_depth(k), h.geometric_normal, probes, o,
                           c)) {
          Rgb e{};
          float used = 0;  // the weight of probes with light towards this pixel's hemisphere
          for (int j = 0; j < c.n; ++j) {
            Rgb mean;
            const float w = c.w[std::size_t(j)];
            if (w <= 0) continue;
            if (!probe_radiance(c.index[std::size_t(j)], n, mean)) continue;
            e += mean * w;
            used += w;
          }
          if (used > 0) l += lobes.diffuse * e * (1 / used);
        }
        const Rgb from_sun = sun_direct ? sun.reflected(h, brdf, wo, local) : Rgb{};
        if (ctx.want_exact) {
          exact.light[k] = emitted + from_sun;
          exact.albedo[k] = lobes.diffuse;
        }
        return l + specular + from_sun;
      });
}

}  // namespace

Expected<ImageRgb> render(const SolveContext& ctx, const SpwiOptions& o, const Layout& layout,
                          SolveReport& report) {
  const cascade::SphereLights lights(ctx.scene, layout.levels);
  // With sphere lights, where each ray of two cascades stopped besides.
  std::uint64_t largest = 0;
  for (int i = 0; i < layout.count(); ++i) largest = std::max(largest, layout.rays(i));
  // With glossy materials, what the cone query keeps of cascades 0..top.
  const int top = cone_top(ctx.scene, layout.levels, o);
  std::vector<KeptCascade> kept(top > 0 ? std::size_t(top) + 1 : 0);
  const std::uint64_t need =
      layout.bytes() + (lights.empty() ? 0 : 2 * largest * sizeof(float)) + cone_bytes(layout, top);
  report.memory_bytes += need;
  if (need > ctx.max_memory)
    return Error{"spwi's cascades need about " + io::format_mib(need) + ", more than the `" +
                 "max_memory` limit of " + io::format_mib(ctx.max_memory)};
  const Background bg(ctx.scene);
  const Surfaces surface{ctx.scene, ctx.cache};
  std::uint64_t rays = 0;
  std::vector<Probe> upper_probes;
  std::vector<float> upper_reach, lower_reach;
  // Cascades from the top down: each merges with the one above, then takes its place.
  const RadianceStore store = cascade::top_down(
      layout.levels, [&](int i, const RadianceStore& upper, RadianceStore& lower) {
        Stopwatch watch;
        std::vector<Probe> probes = place_probes(ctx.scene, ctx.g, layout, i, o);
        std::vector<std::array<Probe, 4>> sub_probes;
        if (o.preaverage) sub_probes = place_sub_probes(ctx.scene, ctx.g, layout, i, o.depth_bias);
        lower.assign(layout.probes(i), layout.map_side(i));
        if (!lights.empty()) lower_reach.assign(std::size_t(layout.rays(i)), -1.0f);
        std::vector<Interval>* own = i < top ? &kept[std::size_t(i)].intervals : nullptr;
        if (own) own->assign(std::size_t(layout.rays(i)), Interval{});
        const ScreenCascade traced{ctx,   o,      layout,      surface,      bg,
                                   i,     probes, sub_probes,  upper_probes, upper,
                                   lower, lights, upper_reach, lower_reach,  own};
        rays += traced.run();
        if (i > 0 && i <= top) {
          KeptCascade& kc = kept[std::size_t(i)];
          kc.probes = probes;
          kc.dirs = cascade::direction_map(layout.levels, i);
          kc.merged = lower;
        }
        upper_probes = std::move(probes);
        std::swap(upper_reach, lower_reach);
        report.stages.push_back({"cascade " + std::to_string(i), watch.ms()});
      });
  Stopwatch watch;
  report.rays += rays;
  ImageRgb img =
      gather(ctx, o, layout, store, upper_probes, bg, surface, kept, report.rays, report.exact);
  report.stages.push_back({"gather", watch.ms()});
  return img;
}

}  // namespace penumbra::spaceland::spwi
