// The probe grid's cascades: their levels, extension, and the top-down trace and merge.
#include "spaceland/grid/grid.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/cascade/cone.hpp"
#include "spaceland/cascade/radiance.hpp"
#include "spaceland/color.hpp"
#include "spaceland/grid/probes.hpp"

namespace penumbra::spaceland::grid {

using cascade::holds_light;
using cascade::kInfinity;
using cascade::kNoLight;
using cascade::RadianceStore;
using cascade::then;

namespace {

// The cascade options' ranges (the voxel size is voxelise's to check).
Status check_cascade_options(const GridOptions& o) {
  if (o.probe_spacing < 1 || o.probe_spacing > 64)
    return Error{"`grid.probe_spacing`: expected 1..64 voxels, found " +
                 std::to_string(o.probe_spacing)};
  const int side = int(std::lround(std::sqrt(double(std::max(0, o.directions)))));
  if (o.directions < 4 || side * side != o.directions || (side & (side - 1)) != 0)
    return Error{
        "`grid.directions`: expected the square of a power of two (4, 16, 64, ...), found " +
        std::to_string(o.directions)};
  if (!std::isfinite(o.interval) || o.interval < 0)
    return Error{"`grid.interval`: expected a length > 0 in world units (0: derived), found " +
                 io::format_number(o.interval)};
  if (o.cascades < 0 || o.cascades > cascade::kMaxCascades)
    return Error{"`grid.cascades`: expected 0.." + std::to_string(cascade::kMaxCascades) +
                 " (0: derived), found " + std::to_string(o.cascades)};
  if (o.fix && o.extend_length > 0)
    return Error{
        "`grid.extend_length`: extension doubles a probe's own intervals, which the bilinear fix "
        "does not use (it traces to the upper probes instead): use one or the other"};
  if (!std::isfinite(o.extend_length) || o.extend_length < 0 ||
      (o.extend_length > 0 && o.extend_length < 1))
    return Error{
        "`grid.extend_length`: expected a traced length of at least 1 voxel (0: no "
        "extension), found " +
        io::format_number(o.extend_length)};
  return {};
}

}  // namespace

Expected<cascade::Levels> grid_levels(const Voxels& v, const GridOptions& o) {
  if (Status s = check_cascade_options(o); !s) return s.error();
  cascade::Levels l;
  l.spacing0 = o.probe_spacing;
  l.side0 = int(std::lround(std::sqrt(double(o.directions))));
  l.spacing_step = l.side_step = l.interval_step = 1;
  // Four probe spacings: the upper probes' spacing stays a half of the distance where their
  // interval starts. At one spacing (twice the distance) shadows wash out: a probe in an umbra
  // takes the light its upper neighbours beside the occluder see (measured, docs/QUALITY.md).
  l.t0 = o.interval > 0 ? o.interval : 4 * float(o.probe_spacing) * v.size;
  const double diagonal =
      double(v.size) * std::sqrt(double(v.nx) * v.nx + double(v.ny) * v.ny + double(v.nz) * v.nz);
  l.count =
      o.cascades > 0 ? o.cascades : cascade::count_to_reach(l, diagonal, cascade::kMaxCascades);
  return l;
}

namespace {

// Each cascade's probe grid over the voxels, from the levels.
std::vector<CascadePlan> cascades_of(const Voxels& v, const cascade::Levels& levels) {
  std::vector<CascadePlan> plan;
  for (int i = 0; i < levels.count; ++i) {
    CascadePlan c;
    c.spacing = levels.spacing(i);
    c.nx = (v.nx + c.spacing - 1) / c.spacing;
    c.ny = (v.ny + c.spacing - 1) / c.spacing;
    c.nz = (v.nz + c.spacing - 1) / c.spacing;
    c.side = levels.side(i);
    c.t_start = levels.interval_start(i);
    c.t_end = levels.interval_end(i);
    plan.push_back(c);
  }
  return plan;
}

}  // namespace

Expected<std::vector<CascadePlan>> plan_cascades(const Voxels& v, const GridOptions& o) {
  Expected<cascade::Levels> levels = grid_levels(v, o);
  if (!levels) return levels.error();
  return cascades_of(v, *levels);
}

int extension_doublings(const CascadePlan& c, const GridOptions& o, float voxel, bool top) {
  if (top || o.fix || o.extend_length <= 0) return 0;
  const double len = double(c.t_end - c.t_start) / voxel;
  int n = 0;
  while (n < 20 && len / double(1 << n) > double(o.extend_length) * (1 + 1e-6)) ++n;
  return n;
}

std::uint64_t cone_bytes(const std::vector<CascadePlan>& plan, int top) {
  std::uint64_t bytes = 0;
  for (int i = 0; top > 0 && i <= top && i < int(plan.size()); ++i) {
    const CascadePlan& c = plan[std::size_t(i)];
    const std::uint64_t rays = c.bytes() / sizeof(Rgb);
    if (i < top) bytes += rays * sizeof(Interval);
    if (i > 0) bytes += c.bytes() + std::uint64_t(c.side) * std::uint64_t(c.side) * sizeof(Vec3);
  }
  return bytes;
}

std::uint64_t cascades_bytes(const std::vector<CascadePlan>& plan, const GridOptions& o,
                             float voxel, bool lights, int cone_top) {
  // What the cone query keeps, besides the largest pair of cascades being solved.
  const std::uint64_t need = cone_bytes(plan, cone_top);
  std::uint64_t solving = 0;
  for (std::size_t i = 0; i < plan.size(); ++i) {
    // Extending holds the cascade's intervals and transmittances twice (a doubling reads one
    // pair and writes the other) and a byte a ray, besides its merged radiance.
    const bool top = i + 1 == plan.size();
    const std::uint64_t rays = plan[i].bytes() / sizeof(Rgb);
    const std::uint64_t extension =
        extension_doublings(plan[i], o, voxel, top) > 0 ? rays * (4 * sizeof(Rgb) + 1) : 0;
    const std::uint64_t pair = plan[i].bytes() + (i + 1 < plan.size() ? plan[i + 1].bytes() : 0);
    // The two cascades' direction maps: past the scene's size a cascade is a probe or two of
    // millions of directions, and its map is as large as its radiance.
    const auto map = [](const CascadePlan& c) {
      return std::uint64_t(c.side) * std::uint64_t(c.side) * sizeof(Vec3);
    };
    const std::uint64_t maps = map(plan[i]) + (i + 1 < plan.size() ? map(plan[i + 1]) : 0);
    // Sphere lights: a float a ray besides its radiance, where it stopped.
    solving = std::max(solving,
                       pair + maps + extension + (lights ? pair / sizeof(Rgb) * sizeof(float) : 0));
  }
  return need + solving;
}

namespace {

// A cascade's intervals traced short and doubled by extension (seed 001 eq. 16):
// L_[a, a+2x](p) = L_[a, a+x](p) + T_[a, a+x](p) L_[a, a+x](p + x w), and T likewise, where the
// shifted interval comes trilinearly from the cascade's own probes of the same direction (a point
// past the grid's box sees nothing along w: the box is convex). `before` marks the rays with a
// surface between the probe and the interval's start.
struct Extended {
  std::vector<Rgb> radiance, transmittance;
  std::vector<std::uint8_t> before;
};

// Calls ray(q, p, d, k) for every probe q of cascade c (at world position p) and direction d
// (k = q * nd + d), rows of probes in parallel.
template <class Ray>
void for_each_ray(const Voxels& v, const CascadePlan& c, std::size_t nd, Ray&& ray) {
  parallel_for(int(c.probes() / std::uint64_t(c.nx)), [&](int row) {
    for (int x = 0; x < c.nx; ++x) {
      const std::uint64_t q = std::uint64_t(row) * c.nx + x;
      const Vec3 p = position_of(v, c, q);
      for (std::size_t d = 0; d < nd; ++d) ray(q, p, d, std::size_t(q) * nd + d);
    }
  });
}

// One doubling: each interval followed by the cascade's own, shifted `shift` along it.
void double_intervals(const Voxels& v, const CascadePlan& c, const std::vector<Vec3>& dirs,
                      float shift, Extended& e, std::vector<Rgb>& radiance,
                      std::vector<Rgb>& transmittance) {
  const std::size_t nd = dirs.size();
  const double box[3] = {double(v.nx) * v.size, double(v.ny) * v.size, double(v.nz) * v.size};
  for_each_ray(v, c, nd, [&](std::uint64_t, Vec3 p, std::size_t d, std::size_t k) {
    radiance[k] = e.radiance[k];
    transmittance[k] = e.transmittance[k];
    if (is_black(e.transmittance[k])) return;
    const Vec3 at = p + dirs[d] * shift;
    for (int a = 0; a < 3; ++a) {
      const double u = double(at[a]) - v.origin[a];
      if (u < 0 || u > box[a]) return;  // nothing out there: T = 1, no light
    }
    const cascade::Corners around = corners(v, c, at);
    Rgb l{}, t{};
    for (int a = 0; a < 8; ++a) {
      const float w = around.w[std::size_t(a)];
      if (w <= 0) continue;
      const std::size_t kk = std::size_t(around.index[std::size_t(a)]) * nd + d;
      l += e.radiance[kk] * w;
      t += e.transmittance[kk] * w;
    }
    radiance[k] += e.transmittance[k] * l;
    transmittance[k] *= t;
  });
  std::swap(radiance, e.radiance);
  std::swap(transmittance, e.transmittance);
}

Extended extend_cascade(const Voxels& v, const CascadePlan& c, const std::vector<Vec3>& dirs,
                        int doublings) {
  const std::size_t nd = dirs.size(), count = std::size_t(c.probes());
  Extended e;
  e.radiance.resize(count * nd);
  e.transmittance.resize(count * nd);
  e.before.assign(count * nd, 0);
  const float piece = (c.t_end - c.t_start) / float(1 << doublings);
  for_each_ray(v, c, nd, [&](std::uint64_t, Vec3 p, std::size_t d, std::size_t k) {
    if (c.t_start > 0) e.before[k] = march(v, p, dirs[d], 0, c.t_start).blocked;
    const Segment s = march(v, p, dirs[d], c.t_start, c.t_start + piece);
    e.radiance[k] = s.radiance;
    e.transmittance[k] = s.blocked ? Rgb{} : s.transmittance;
  });
  std::vector<Rgb> radiance(count * nd), transmittance(count * nd);
  for (int j = 0; j < doublings; ++j)
    double_intervals(v, c, dirs, piece * float(1 << j), e, radiance, transmittance);
  return e;
}

// The grid's tracer for the cascade core: the voxel march; what leaves the grid sees the sky.
struct VoxelTracer {
  const Voxels& v;
  const Background& bg;
  Segment trace(Vec3 origin, Vec3 dir, float t0, float t1) const {
    return march(v, origin, dir, t0, t1);
  }
  Rgb sky(Vec3 d) const { return bg.sky(d); }
};

// One cascade of the grid, traced and merged with the one above.
struct GridCascade {
  const Voxels& v;
  const GridOptions& o;
  const CascadePlan& c;
  const CascadePlan* up;  // null for the top cascade
  const std::vector<Vec3>& dirs;
  const std::vector<Vec3>& up_dirs;
  const RadianceStore& upper;
  const Extended& ext;
  int doublings;
  VoxelTracer tracer;
  const cascade::SphereLights* lights;
  // With sphere lights: where each ray of the cascade above stopped (read) and of this one
  // (written), probe-major (-1: a probe inside a surface, no ray; 0: stopped before its interval;
  // infinity: no surface met, or not known with the fix).
  const std::vector<float>* upper_reach;
  std::vector<float>* lower_reach;
  // Cascade 0: its share of the sphere lights is met at the points that read it.
  bool claims_at_points;
  // Where the cone query keeps this cascade's own intervals (null: it does not), probe-major.
  Interval* own;
  // The fix traces from each interval's start to the upper probes': no ray needs to know whether
  // a surface lies before its interval.
  bool fix = o.fix && up;

  // The upper probes around probe p. One this probe cannot see (across a wall or a floor) would
  // bring light from the other side: it takes no part (the 2D cascades weigh by visibility too).
  // With the fix, neither does one inside a surface (it holds no light).
  cascade::Corners upper_corners(Vec3 p, Vec3 (&upper_probe)[8]) const {
    cascade::Corners around = corners(v, *up, p);
    for (int j = 0; j < 8; ++j) {
      float& w = around.w[std::size_t(j)];
      if (w <= 0) continue;
      const std::uint64_t uq = around.index[std::size_t(j)];
      upper_probe[j] = position_of(v, *up, uq);
      const Vec3 to = upper_probe[j] - p;
      const float dist = length(to);
      if (dist > 0 && march(v, p, to * (1 / dist), 0, dist).blocked) w = 0;
      if (fix && !holds_light(upper.at(uq, 0))) w = 0;
    }
    return around;
  }

  // The bilinear fix: each child direction to each upper probe's interval start, then that
  // probe's light along the child direction.
  // `in`, where kept: the pieces' mean radiance and transmittance (U and T of the cone query).
  Rgb fixed_ray(Vec3 p, const cascade::Corners& around, const Vec3 (&upper_probe)[8], int du,
                int dv, Interval* in) const {
    const std::size_t up_side = std::size_t(up->side);
    Rgb sum{}, met{}, through{};
    float weight = 0;
    for (int j = 0; j < 8; ++j) {
      const float w = around.w[std::size_t(j)];
      const std::uint64_t uq = around.index[std::size_t(j)];
      if (w <= 0) continue;
      Rgb mean{};
      for (int cv = 0; cv < 2; ++cv)
        for (int cu = 0; cu < 2; ++cu) {
          const std::size_t ud = std::size_t(2 * dv + cv) * up_side + std::size_t(2 * du + cu);
          const Vec3 from = p + up_dirs[ud] * c.t_start;
          const Vec3 to = upper_probe[j] + up_dirs[ud] * up->t_start - from;
          const float dist = length(to);
          const Segment s = dist > 0 ? march(v, from, to * (1 / dist), 0, dist) : Segment{};
          mean += then(s, upper.at(uq, ud));
          if (in) {
            met += s.radiance * (w / 4);
            if (!s.blocked) through += s.transmittance * (w / 4);
          }
        }
      sum += mean * (w / 4);
      weight += w;
    }
    if (weight > 0) {
      if (in) *in = {met * (1 / weight), through * (1 / weight)};
      return sum * (1 / weight);
    }
    // No upper probe seen: the ray traces its interval and on to the sky.
    const Rgb l =
        cascade::continue_to_sky(tracer, p, dirs[std::size_t(dv) * c.side + du], c.t_start);
    if (in) *in = {l, Rgb{}};
    return l;
  }

  // The ray's own interval, from the probe (a surface between the probe and the interval's start
  // leaves it unusable for the cascade below: false).
  bool interval(std::uint64_t q, Vec3 p, std::size_t d, Segment& s) const {
    if (doublings > 0) {
      const std::size_t k = std::size_t(q) * dirs.size() + d;
      if (ext.before[k]) return false;
      s.radiance = ext.radiance[k];
      s.transmittance = ext.transmittance[k];
      s.blocked = is_black(s.transmittance);
      s.t_end = s.blocked ? c.t_start : c.t_end;  // where it stopped is not kept: at the start
      return true;
    }
    if (!o.fix && c.t_start > 0 && march(v, p, dirs[d], 0, c.t_start).blocked) return false;
    s = march(v, p, dirs[d], c.t_start, c.t_end);
    return true;
  }

  // Direction (du, dv) of probe q: its interval, merged with the upper probes around it; `reach`
  // is where its ray stopped, its merged continuation included (infinity: at no surface, or not
  // known, with the fix).
  // `in`, where kept: the interval's own radiance and transmittance (U and T of the cone query;
  // T 0 where nothing above continues it).
  Rgb ray(std::uint64_t q, Vec3 p, const cascade::Corners& around, int du, int dv, float& reach,
          Interval* in) const {
    const std::size_t d = std::size_t(dv) * c.side + du;
    reach = 0;  // stopped before its interval
    Segment s;
    if (!interval(q, p, d, s)) return kNoLight;
    reach = kInfinity;
    if (s.blocked) reach = s.t_end;
    Rgb l;
    if (s.blocked || !up) {
      l = then(s, tracer.sky(dirs[d]));
    } else if (Rgb merged; cascade::merge_children(upper, around, du, dv, 2, merged)) {
      if (lights && !lights->empty()) {
        reach =
            cascade::merged_reach(around, du, dv, 2, upper_reach->data(), up->side, up->t_start);
      }
      if (in) *in = {s.radiance, s.transmittance};
      return s.radiance + s.transmittance * merged;
    } else {
      // No upper probe has light this way: the ray continues itself to the sky.
      l = then(s, cascade::continue_to_sky(tracer, p, dirs[d], c.t_end, &reach));
    }
    if (in) *in = {l, Rgb{}};
    return l;
  }

  // Returns the rays it traced (none for a probe inside a surface).
  std::uint64_t probe(std::uint64_t q, Rgb* out) const {
    const std::size_t nd = dirs.size();
    // A probe inside a surface serves no one (those above: no probe below sees it).
    if (!probe_free(v, c, q)) {
      std::fill(out, out + nd, kNoLight);
      return 0;
    }
    const Vec3 p = position_of(v, c, q);
    cascade::Corners around;
    Vec3 upper_probe[8] = {};
    if (up) around = upper_corners(p, upper_probe);
    const bool spread = lights && !lights->empty();
    float* reach = spread ? lower_reach->data() + std::size_t(q) * nd : nullptr;
    Interval* in = own ? own + std::size_t(q) * nd : nullptr;
    float r = kInfinity;
    for (int dv = 0; dv < c.side; ++dv)
      for (int du = 0; du < c.side; ++du) {
        const std::size_t k = std::size_t(dv) * c.side + du;
        Interval* ik = in ? in + k : nullptr;
        out[k] =
            fix ? fixed_ray(p, around, upper_probe, du, dv, ik) : ray(q, p, around, du, dv, r, ik);
        if (spread) reach[k] = !fix ? r : holds_light(out[k]) ? kInfinity : 0.0f;
      }
    // Its share of the sphere lights left out of the voxels, in the cells whose ray got past them
    // (cascade 0 leaves its share to the points that read it: RadianceField::lights_at). The cone
    // query keeps it in U too: the light lies inside this cascade's interval.
    if (!spread || claims_at_points) return nd;
    thread_local std::vector<Rgb> before;
    if (in) before.assign(out, out + nd);
    const cascade::Uppers ups = cascade::uppers_of(around, up ? up->t_start : 0,
                                                   [&](std::size_t j) { return upper_probe[j]; });
    const std::size_t up_cells = up ? std::size_t(up->side) * std::size_t(up->side) : 0;
    lights->add(
        p, Vec3{}, c.t_start, c.t_end, up ? &ups : nullptr, c.side, out,
        [&](std::size_t k, float dist) { return reach[k] >= dist ? 1.0f : 0.0f; },
        [&](const cascade::SphereLight& l) {
          if (!up) return 1.0f;
          return cascade::upper_clear(ups, up->side, l, [&](std::size_t j, std::size_t k) {
            return (*upper_reach)[std::size_t(around.index[j]) * up_cells + k];
          });
        });
    if (in)
      for (std::size_t k = 0; k < nd; ++k)
        if (holds_light(in[k].radiance)) in[k].radiance += out[k] - before[k];
    return nd;
  }
};

}  // namespace

struct CascadeSolve::State {
  const Voxels* v = nullptr;
  GridOptions o;
  const cascade::SphereLights* lights = nullptr;
  cascade::Levels levels;
  std::vector<CascadePlan> plan;
  bool spread = false;
  int cone_top = 0;
  int i = -1;          // the cascade at hand (-1: all done)
  int z = 0;           // its next layer of probes
  bool begun = false;  // its directions and stores made
  std::uint64_t slabs = 0, done = 0;
  RadianceStore upper, lower;
  std::vector<Vec3> dirs, up_dirs;  // this cascade's directions and the one above's
  std::vector<float> upper_reach, lower_reach;
  Extended ext;
  int doublings = 0;
  std::uint64_t traced = 0;
  std::vector<double> ms;
  // What the cone query reads of cascades 0..top: their own intervals below top, their merged
  // radiance and directions above 0 (cascade 0's are the field's).
  std::vector<RadianceField::Kept> kept;

  // Cascade i's directions, store and extension, before its first layer.
  void begin() {
    const CascadePlan& c = plan[std::size_t(i)];
    dirs = {};  // map i + 2's, freed before map i is made (two maps at once, as estimated)
    dirs = cascade::direction_map(levels, i);
    lower.assign(c.probes(), c.side);
    if (spread) {
      const std::size_t rays = std::size_t(c.probes()) * std::size_t(c.side) * c.side;
      if (rays != lower_reach.capacity()) lower_reach = {};  // never old and new at once
      lower_reach.assign(rays, -1.0f);
    }
    doublings = extension_doublings(c, o, v->size, levels.top(i));
    ext = doublings > 0 ? extend_cascade(*v, c, dirs, doublings) : Extended{};
    if (i < cone_top)
      kept[std::size_t(i)].intervals.assign(std::size_t(c.probes()) * dirs.size(), {});
    begun = true;
  }

  // Layers [z, z + n) of cascade i.
  void layers(const Background& bg, int n) {
    const CascadePlan& c = plan[std::size_t(i)];
    const bool top = levels.top(i);
    const GridCascade solver{*v,
                             o,
                             c,
                             top ? nullptr : &plan[std::size_t(i) + 1],
                             dirs,
                             up_dirs,
                             upper,
                             ext,
                             doublings,
                             VoxelTracer{*v, bg},
                             lights,
                             &upper_reach,
                             &lower_reach,
                             i == 0,
                             i < cone_top ? kept[std::size_t(i)].intervals.data() : nullptr};
    std::atomic<std::uint64_t> count{0};
    const int first = z;
    parallel_for(n, [&](int k) {
      std::uint64_t local = 0;
      const std::uint64_t layer = std::uint64_t(c.ny) * c.nx;
      for (std::uint64_t q = std::uint64_t(first + k) * layer, end = q + layer; q < end; ++q)
        local += solver.probe(q, lower.probe(q));
      count.fetch_add(local, std::memory_order_relaxed);
    });
    traced += count.load();
    z += n;
  }

  // Cascade i merged: it becomes the upper of the one below.
  void end() {
    if (i > 0 && i <= cone_top) {
      kept[std::size_t(i)].merged = lower;
      kept[std::size_t(i)].dirs = dirs;
    }
    std::swap(upper, lower);
    std::swap(up_dirs, dirs);
    std::swap(upper_reach, lower_reach);
    ext = Extended{};
    --i;
    z = 0;
    begun = false;
  }
};

CascadeSolve::CascadeSolve(std::unique_ptr<State> s) : s_(std::move(s)) {}
CascadeSolve::CascadeSolve(CascadeSolve&&) noexcept = default;
CascadeSolve& CascadeSolve::operator=(CascadeSolve&&) noexcept = default;
CascadeSolve::~CascadeSolve() = default;

Expected<CascadeSolve> CascadeSolve::start(const Voxels& v, const GridOptions& o,
                                           std::uint64_t max_bytes,
                                           const cascade::SphereLights* lights, float narrowest) {
  Expected<cascade::Levels> levels = grid_levels(v, o);
  if (!levels) return levels.error();
  auto s = std::make_unique<State>();
  s->v = &v;
  s->o = o;
  s->lights = lights;
  s->levels = *levels;
  s->plan = cascades_of(v, *levels);
  s->spread = lights && !lights->empty();
  s->cone_top = o.specular == SpecularQuery::cone ? cascade::cone_top(*levels, narrowest) : 0;
  const std::uint64_t need = cascades_bytes(s->plan, o, v.size, s->spread, s->cone_top);
  if (need > max_bytes)
    return Error{"the probe grid's cascades need " +
                 io::format_rounded(double(need) / double(1 << 20)) +
                 " MiB, more than the `max_memory` limit of " +
                 io::format_rounded(double(max_bytes) / double(1 << 20)) +
                 " MiB; use a larger --voxel or fewer --directions" +
                 (s->cone_top > 0 ? std::string(", or --specular wide (the cone query keeps "
                                                "cascades 0..") +
                                        std::to_string(s->cone_top) + " for the glossy materials)"
                                  : std::string())};
  s->i = levels->count - 1;
  for (const CascadePlan& c : s->plan) s->slabs += std::uint64_t(c.nz);
  s->ms.assign(s->plan.size(), 0.0);
  s->kept.resize(s->cone_top > 0 ? std::size_t(s->cone_top) + 1 : 0);
  return CascadeSolve(std::move(s));
}

bool CascadeSolve::step(const Background& bg, std::uint64_t& slabs) {
  State& s = *s_;
  while (s.i >= 0 && slabs > 0) {
    Stopwatch watch;
    if (!s.begun) s.begin();
    const int nz = s.plan[std::size_t(s.i)].nz;
    const int n = int(std::min<std::uint64_t>(slabs, std::uint64_t(nz - s.z)));
    s.layers(bg, n);
    slabs -= std::uint64_t(n);
    s.done += std::uint64_t(n);
    s.ms[std::size_t(s.i)] += watch.ms();
    if (s.z == nz) s.end();
  }
  return s.i < 0;
}

std::uint64_t CascadeSolve::slabs() const {
  return s_->slabs;
}

std::uint64_t CascadeSolve::done() const {
  return s_->done;
}

RadianceField CascadeSolve::finish() {
  State& s = *s_;
  // cascade 0's directions and store, swapped up last
  RadianceField f = RadianceField::make(*s.v, std::move(s.plan), std::move(s.up_dirs),
                                        std::move(s.upper), std::move(s.ms));
  f.rays_ = s.traced;
  f.kept_ = std::move(s.kept);
  f.levels_ = s.levels;
  if (s.spread) {
    f.lights_ = *s.lights;
    f.reach_ = std::move(s.upper_reach);                           // cascade 0's, swapped up last
    if (f.plan_.size() > 1) f.reach1_ = std::move(s.lower_reach);  // and cascade 1's before it
  }
  return f;
}

Expected<RadianceField> solve(const Voxels& v, const Background& bg, const GridOptions& o,
                              std::uint64_t max_bytes, const cascade::SphereLights* lights,
                              float narrowest) {
  Expected<CascadeSolve> s = CascadeSolve::start(v, o, max_bytes, lights, narrowest);
  if (!s) return s.error();
  std::uint64_t all = s->slabs();
  s->step(bg, all);
  return s->finish();
}

RadianceField RadianceField::make(const Voxels& v, std::vector<CascadePlan> plan,
                                  std::vector<Vec3> dirs, RadianceStore radiance,
                                  std::vector<double> ms) {
  RadianceField f;
  f.cascade_ms_ = std::move(ms);
  f.voxels_ = &v;
  f.plan_ = std::move(plan);
  f.dirs_ = std::move(dirs);
  f.radiance_ = std::move(radiance);
  const std::size_t nd = f.dirs_.size();
  const CascadePlan& c0 = f.plan_[0];
  f.valid_.resize(std::size_t(c0.probes()));
  f.sphere_.resize(std::size_t(c0.probes()));
  const std::uint64_t row = std::uint64_t(c0.nx);
  parallel_for(int(c0.probes() / row), [&](int r) {
    for (std::uint64_t q = std::uint64_t(r) * row; q < std::uint64_t(r + 1) * row; ++q) {
      f.valid_[std::size_t(q)] = probe_free(v, c0, q);
      if (!f.valid_[std::size_t(q)]) continue;
      // Equal-area cells: the plain mean is the mean over the sphere.
      Rgb sum{};
      const Rgb* probe = f.radiance_.probe(q);
      for (std::size_t d = 0; d < nd; ++d) sum += probe[d];
      f.sphere_[std::size_t(q)] = sum * (1 / float(nd));
    }
  });
  return f;
}

Status check_options(const GridOptions& o) {
  if (!std::isfinite(o.voxel) || o.voxel < 0)
    return Error{"`grid.voxel`: expected a voxel size > 0 in world units (0: derived), found " +
                 io::format_number(o.voxel)};
  // The outermost level (136 voxels, doubling per level) stays within the coordinates the ray
  // tracer takes (Embree: 1.8e18) wherever the camera stands.
  if (o.voxel > kMaxCoordinate / 100)
    return Error{"`grid.voxel`: expected at most " + io::format_number(kMaxCoordinate / 100) +
                 " world units (a hundredth of the largest world coordinate), found " +
                 io::format_number(o.voxel)};
  if (o.levels < 0 || o.levels > kMaxLevels)
    return Error{"`grid.levels`: expected 1.." + std::to_string(kMaxLevels) +
                 " (0: derived), found " + std::to_string(o.levels)};
  if (o.levels > 1 && o.extend_length > 0)
    return Error{
        "`grid.levels`: extension reads a cascade's own probes along its rays, which a level "
        "does not have past its box: with extension the grid is one level (1)"};
  if (o.specular != SpecularQuery::cone && o.specular != SpecularQuery::wide)
    return Error{
        "`grid.specular`: expected cone or wide (the exact mirror ray is spwi's "
        "baseline)"};
  return check_cascade_options(o);
}

}  // namespace penumbra::spaceland::grid
