// The direct radiance field renderer (seed 001 section 4.4): surface radiance cascades on one
// window, each interval path-traced. docs/METHODS.md, "The direct radiance field".
#include "penumbra/spaceland/field.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include "core/d3.hpp"
#include "core/math.hpp"
#include "core/octahedral.hpp"
#include "core/parallel.hpp"
#include "core/sobol.hpp"
#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/atlas/cascades.hpp"
#include "spaceland/brightness.hpp"
#include "spaceland/camera.hpp"
#include "spaceland/cascade/levels.hpp"
#include "spaceland/color.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/pt/pt.hpp"
#include "spaceland/scene/check.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// The window's frame: unit x along u, y along v, n = x cross y (behind the window).
struct Frame {
  Vec3 corner, x, y, n;
  float len_u = 0, len_v = 0;

  // In double: an edge of 1e-23 squares to nothing in float (check_field_options bounds them).
  explicit Frame(const Window& w) : corner(w.corner) {
    const D3 u = d3(w.u), v = d3(w.v);
    const double lu = std::sqrt(dot(u, u)), lv = std::sqrt(dot(v, v));
    len_u = float(lu);
    len_v = float(lv);
    x = f3((1 / lu) * u);
    y = f3((1 / lv) * v);
    n = normalize(cross(x, y));
  }
  Vec3 at(float s, float t) const { return corner + x * (s * len_u) + y * (t * len_v); }
  Vec3 to_world(Vec3 d) const { return x * d.x + y * d.y + n * d.z; }
  Vec3 to_local(Vec3 d) const { return {dot(d, x), dot(d, y), dot(d, n)}; }
  // Where the ray from o along unit d crosses the window towards the field: its (s, t).
  bool crossing(Vec3 o, Vec3 d, float& s, float& t, Vec3& p) const {
    const float facing = dot(d, n);
    if (!(facing > 0)) return false;
    const float along = dot(corner - o, n) / facing;
    if (!(along >= 0)) return false;
    p = o + d * along;
    s = dot(p - corner, x) / len_u;
    t = dot(p - corner, y) / len_v;
    return s >= 0 && s <= 1 && t >= 0 && t <= 1;
  }
};

// The hemisphere behind the window as a square: the equal-area octahedral map's upper diamond
// |e0| + |e1| <= 1 turned 45 degrees, (a, b) = (e0 + e1, e0 - e1) in [-1, 1]^2. Equal cells still
// hold equal solid angles (the turn is linear), and the square's edge is the horizon.
std::array<float, 2> hemi_encode(Vec3 local) {
  local.z = std::max(local.z, 0.0f);  // a direction in front of the window reads the horizon
  const float len = length(local);
  // Straight out of the window (-n) has no nearest horizon direction: it reads one of them.
  const std::array<float, 2> e = octahedral::encode(len > 0 ? local / len : Vec3{1, 0, 0});
  return {std::clamp(e[0] + e[1], -1.0f, 1.0f), std::clamp(e[0] - e[1], -1.0f, 1.0f)};
}

Vec3 hemi_decode(double a, double b) {
  return octahedral::decode((a + b) / 2, (a - b) / 2);
}

// Bilinear taps of a continuous coordinate over n cells (centres at 0.5, 1.5, ...), clamped.
struct Taps {
  int i0, i1;
  float w1;
};
Taps taps(float c, int n) {
  const float f = c - 0.5f;
  const float fl = std::floor(f);
  const int i = int(fl);
  return {std::clamp(i, 0, n - 1), std::clamp(i + 1, 0, n - 1), f - fl};
}

// One direction of one probe: the interval's radiance and its transmittance.
struct Cell {
  Rgb L{}, T{};
};

struct Cascade {
  int nu = 0, nv = 0, side = 0;
  float start = 0, end = 0;
  // Where its lead-in begins: the interval below's start (docs/METHODS.md, "The direct radiance
  // field"): a surface between there and `start` is this interval's, opaque.
  float lead_from = 0;
  // Per probe (row by row), per direction (row by row): a view reads a cell's two together.
  std::vector<Cell> cells;
};

}  // namespace

struct RadianceField::Impl {
  FieldOptions o;
  Frame frame{Window{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  int nu0 = 0, nv0 = 0;
  std::vector<Cascade> c;
  int light_exponent = 0;
  std::vector<StageTime> stages;
  double bake_ms = 0;
  std::uint64_t memory = 0, rays = 0;

  // Cascade i's interval radiance (L) and transmittance (T) at (s, t) towards hemisphere point
  // (a, b): 2 x 2 probes times 2 x 2 directions.
  void lookup(int i, float s, float t, float a, float b, Rgb& L, Rgb& T) const {
    const Cascade& k = c[std::size_t(i)];
    const Taps x = taps(s * float(k.nu), k.nu);
    const Taps y = taps(t * float(k.nv), k.nv);
    const Taps da = taps((a + 1) * 0.5f * float(k.side), k.side);
    const Taps db = taps((b + 1) * 0.5f * float(k.side), k.side);
    const std::size_t q = std::size_t(k.side) * std::size_t(k.side);
    L = Rgb{};
    T = Rgb{};
    const int px[2] = {x.i0, x.i1}, py[2] = {y.i0, y.i1}, ua[2] = {da.i0, da.i1},
              vb[2] = {db.i0, db.i1};
    const float wx[2] = {1 - x.w1, x.w1}, wy[2] = {1 - y.w1, y.w1}, wa[2] = {1 - da.w1, da.w1},
                wb[2] = {1 - db.w1, db.w1};
    for (int jy = 0; jy < 2; ++jy)
      for (int jx = 0; jx < 2; ++jx) {
        const std::size_t probe = std::size_t(py[jy]) * std::size_t(k.nu) + std::size_t(px[jx]);
        const float wp = wx[jx] * wy[jy];
        if (wp == 0) continue;
        for (int jb = 0; jb < 2; ++jb)
          for (int ja = 0; ja < 2; ++ja) {
            const float w = wp * wa[ja] * wb[jb];
            if (w == 0) continue;
            const std::size_t at =
                probe * q + std::size_t(vb[jb]) * std::size_t(k.side) + std::size_t(ua[ja]);
            L += k.cells[at].L * w;
            T += k.cells[at].T * w;
          }
      }
  }

  // L0 + T0 (L1 + T1 (...)), front to back.
  Rgb radiance(float s, float t, Vec3 towards) const {
    const std::array<float, 2> ab = hemi_encode(frame.to_local(towards));
    Rgb sum{}, through{1, 1, 1};
    for (std::size_t i = 0; i < c.size(); ++i) {
      Rgb L, T;
      lookup(int(i), s, t, ab[0], ab[1], L, T);
      sum += through * L;
      through *= T;
      if (is_black(through)) break;
    }
    return light_exponent ? sum * std::ldexp(1.0f, light_exponent) : sum;
  }
};

namespace {

// The most cascades whose top map stays within 4096 a side (16.7 M directions a probe).
int most_cascades(int side0) {
  int n = 1;
  while (n < cascade::kMaxCascades && (side0 << n) <= 4096) ++n;
  return n;
}

}  // namespace

Status check_field_options(const FieldOptions& o) {
  const Window& w = o.window;
  const auto finite = [](Vec3 p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  };
  if (!finite(w.corner) || !finite(w.u) || !finite(w.v))
    return Error{"`window`: expected finite numbers"};
  // Its corners within the format's coordinates (Embree's ray origins, squared distances).
  for (const Vec3 p : {w.corner, w.corner + w.u, w.corner + w.v, w.corner + w.u + w.v})
    if (!inside_world(p))
      return Error{"`window`: its corners must lie within +-" + std::to_string(kMaxCoordinate) +
                   " on each axis"};
  const D3 u = d3(w.u), v = d3(w.v);
  const double lu = std::sqrt(dot(u, u)), lv = std::sqrt(dot(v, v));
  if (!(lu >= 1e-30) || !(lv >= 1e-30))
    return Error{"`window`: its edges u and v must be at least 1e-30 long"};
  if (std::abs(dot(u, v)) > 1e-4 * lu * lv)
    return Error{"`window`: expected a rectangle, its edges u and v at right angles"};
  if (o.texels < 1 || o.texels > 4096)
    return Error{"`texels`: expected 1..4096, found " + std::to_string(o.texels)};
  if (atlas::side_of(o.directions) == 0)
    return Error{"`directions`: expected 4, 16, 64, 256, 1024 or 4096, found " +
                 std::to_string(o.directions)};
  if (!(o.interval >= 0) || !(o.interval <= kMaxCoordinate))
    return Error{"`interval`: expected 0.." + std::to_string(kMaxCoordinate) + ", found " +
                 std::to_string(o.interval)};
  if (const int most = most_cascades(atlas::side_of(o.directions));
      atlas::side_of(o.directions) && (o.cascades < 0 || o.cascades > most))
    return Error{"`cascades`: expected 0.." + std::to_string(most) + " at " +
                 std::to_string(o.directions) +
                 " directions (the top cascade's map at most 4096 a side), found " +
                 std::to_string(o.cascades)};
  if (o.spp < 1 || o.spp > 1 << 20)
    return Error{"`spp`: expected 1..1048576, found " + std::to_string(o.spp)};
  if (o.bounces < 1 || o.bounces > 64)
    return Error{"`bounces`: expected 1..64, found " + std::to_string(o.bounces)};
  if (o.threads < 0 || o.threads > 1024)
    return Error{"`threads`: expected 0..1024, found " + std::to_string(o.threads)};
  return {};
}

namespace {

// The hierarchy a bake of these options makes (stores not allocated): probes, maps, intervals.
std::vector<Cascade> plan(const Scene& scene, const FieldOptions& o, int& nu0, int& nv0,
                          float& t0) {
  const Frame f(o.window);
  const float texel = std::max(f.len_u, f.len_v) / float(o.texels);
  nu0 = std::max(1, int(std::lround(f.len_u / texel)));
  nv0 = std::max(1, int(std::lround(f.len_v / texel)));
  cascade::Levels l;
  l.side0 = atlas::side_of(o.directions);
  l.spacing_step = 1;
  l.side_step = 1;
  l.interval_step = 2;
  l.t0 = o.interval > 0 ? o.interval : 2 * texel;
  // The intervals reach from the window to the farthest corner of the surfaces and fog boxes.
  double reach = 0;
  auto reach_to = [&](Vec3 corner) {
    for (float s : {0.0f, 1.0f})
      for (float t : {0.0f, 1.0f}) {
        const D3 gap = d3(corner) - d3(f.at(s, t));
        reach = std::max(reach, std::sqrt(dot(gap, gap)));
      }
  };
  const Bounds b = scene_bounds(scene);
  for (int k = 0; k < 8; ++k)
    reach_to({(k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z});
  for (const Medium& m : scene.media)
    for (int k = 0; k < 8; ++k)
      reach_to(m.center + m.axes[0] * ((k & 1) ? m.half_size.x : -m.half_size.x) +
               m.axes[1] * ((k & 2) ? m.half_size.y : -m.half_size.y) +
               m.axes[2] * ((k & 4) ? m.half_size.z : -m.half_size.z));
  // Past the cascade whose probes span the window's shorter side in one, a cascade would halve
  // the probes along one side only while it quadruples the directions: the derived count stops
  // there (the top interval runs on to infinity anyway), so the cascades keep M_i = M_0 (up to
  // rounding the probe counts up) whatever the scene's size.
  int single = 1;
  while ((1 << (single - 1)) < std::min(nu0, nv0)) ++single;
  l.count = o.cascades > 0
                ? o.cascades
                : cascade::count_to_reach(l, reach, std::min(single, most_cascades(l.side0)));
  t0 = l.t0;
  std::vector<Cascade> out(std::size_t(l.count));
  for (int i = 0; i < l.count; ++i) {
    Cascade& k = out[std::size_t(i)];
    const int step = 1 << i;
    k.nu = (nu0 + step - 1) / step;
    k.nv = (nv0 + step - 1) / step;
    k.side = l.side(i);
    k.start = l.interval_start(i);
    k.lead_from = o.lead_in && i > 0 ? l.interval_start(i - 1) : k.start;
    k.end = l.interval_end(i);
  }
  return out;
}

std::uint64_t cascade_bytes(const Cascade& k) {
  return std::uint64_t(k.nu) * std::uint64_t(k.nv) * std::uint64_t(k.side) * std::uint64_t(k.side) *
         2 * sizeof(Rgb);
}

}  // namespace

namespace {

// What a bake of these cascades holds: the ray tracer, every store, and a dimmed copy of the
// scene where its light is scaled (exponent > 0).
std::uint64_t held_bytes(const Scene& scene, const std::vector<Cascade>& cascades, int exponent) {
  std::uint64_t bytes = RayScene::estimate_bytes(scene) + (exponent > 0 ? scene_bytes(scene) : 0);
  for (const Cascade& k : cascades) bytes += cascade_bytes(k);
  return bytes;
}

}  // namespace

std::uint64_t estimate_field_memory(const Scene& scene, const FieldOptions& o) {
  if (!check_field_options(o)) return 0;
  int nu0 = 0, nv0 = 0;
  float t0 = 0;
  const Expected<int> e = light_exponent(scene, o.bounces);
  return held_bytes(scene, plan(scene, o, nu0, nv0, t0), e ? *e : 0);
}

RadianceField::RadianceField(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RadianceField::RadianceField(RadianceField&&) noexcept = default;
RadianceField& RadianceField::operator=(RadianceField&&) noexcept = default;
RadianceField::~RadianceField() = default;

Expected<RadianceField> RadianceField::bake(const Scene& in, const FieldOptions& o) {
  if (Status s = check_field_options(o); !s) return s.error();
  if (Status s = check_scene(in); !s) return s.error();
  Expected<int> k = light_exponent(in, o.bounces);
  if (!k) return k.error();
  Stopwatch total;
  auto impl = std::make_unique<Impl>();
  impl->o = o;
  impl->frame = Frame(o.window);
  impl->light_exponent = *k;
  float t0 = 0;
  impl->c = plan(in, o, impl->nu0, impl->nv0, t0);
  const std::uint64_t need = held_bytes(in, impl->c, *k) + scene_bytes(in);
  if (need > o.max_memory)
    return Error{"the radiance field needs " + std::to_string(need >> 20) +
                 " MiB of working memory, over the limit of " + std::to_string(o.max_memory >> 20) +
                 " MiB (fewer texels, directions or cascades need less)"};
  impl->o.interval = t0;
  impl->o.cascades = int(impl->c.size());
  if (!(impl->c.back().start <= kMaxCoordinate))
    return Error{"`interval`: the top cascade would start " + std::to_string(impl->c.back().start) +
                 " from the window, past the coordinates' limit of " +
                 std::to_string(kMaxCoordinate) + " (a smaller interval or fewer cascades)"};

  const Scene dim = *k > 0 ? dimmed(in, *k) : Scene{};
  const Scene& scene = *k > 0 ? dim : in;
  Stopwatch watch;
  Expected<RayScene> rays = RayScene::build(scene, o.max_memory);
  if (!rays) return rays.error();
  impl->stages.push_back({"ray tracer", watch.ms()});
  impl->memory = held_bytes(scene, impl->c, *k);

  const pt::SegmentTracer tracer(scene, *rays, o.bounces);
  const std::uint32_t base = sobol::hash(o.seed);
  std::atomic<std::uint64_t> ray_count{0};
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  const Frame& f = impl->frame;
  for (std::size_t i = 0; i < impl->c.size(); ++i) {
    watch.restart();
    Cascade& c = impl->c[i];
    const std::size_t q = std::size_t(c.side) * std::size_t(c.side);
    const std::size_t cells = std::size_t(c.nu) * std::size_t(c.nv) * q;
    c.cells.assign(cells, Cell{});
    const std::uint32_t cascade_seed = sobol::hash((std::uint64_t(base) << 32) | i);
    const float length = c.end - c.start;
    // Blocks of one probe's row of directions: enough tasks for the top cascade's few probes.
    const std::size_t rows = std::size_t(c.nu) * std::size_t(c.nv) * std::size_t(c.side);
    arena.execute([&] {
      parallel_for(int(rows), [&](int row) {
        const std::size_t probe = std::size_t(row) / std::size_t(c.side);
        const int vb = row % c.side;
        const int px = int(probe % std::size_t(c.nu)), py = int(probe / std::size_t(c.nu));
        // Cascade i's ceil(n0 / 2^i) probes a side split the window evenly (2^i texels apart
        // where 2^i divides n0), each at the centre of its part, so that every probe stands on
        // the window and reading needs no other layout.
        const Vec3 p = f.at((float(px) + 0.5f) / float(c.nu), (float(py) + 0.5f) / float(c.nv));
        std::vector<MediumPiece> pieces;
        std::uint64_t local = 0;
        for (int ua = 0; ua < c.side; ++ua) {
          const std::size_t at =
              probe * q + std::size_t(vb) * std::size_t(c.side) + std::size_t(ua);
          const std::uint32_t seed = sobol::hash((std::uint64_t(cascade_seed) << 32) | at);
          const std::uint32_t jitter = sobol::hash(~std::uint64_t(seed));
          double sum[6] = {0, 0, 0, 0, 0, 0};
          for (int s = 0; s < o.spp; ++s) {
            // Each sample's direction is uniform over the cell (equal area): the stored value is
            // the cell's mean, which the view's bilinear reading assumes.
            const std::array<float, 2> u = sobol::sample_2d(std::uint32_t(s), jitter, 0);
            const Vec3 d = f.to_world(hemi_decode(2 * (ua + double(u[0])) / c.side - 1,
                                                  2 * (vb + double(u[1])) / c.side - 1));
            const pt::Segment g = tracer.trace(p + d * c.start, d, length, c.start - c.lead_from,
                                               seed, std::uint32_t(s), pieces, local);
            if (!std::isfinite(g.radiance.r + g.radiance.g + g.radiance.b)) continue;
            sum[0] += g.radiance.r;
            sum[1] += g.radiance.g;
            sum[2] += g.radiance.b;
            sum[3] += g.transmittance.r;
            sum[4] += g.transmittance.g;
            sum[5] += g.transmittance.b;
          }
          const double inv = 1.0 / o.spp;
          c.cells[at] = Cell{Rgb{float(sum[0] * inv), float(sum[1] * inv), float(sum[2] * inv)},
                             Rgb{float(sum[3] * inv), float(sum[4] * inv), float(sum[5] * inv)}};
        }
        ray_count.fetch_add(local, std::memory_order_relaxed);
      });
    });
    impl->stages.push_back({"cascade " + std::to_string(i), watch.ms()});
  }
  impl->rays = ray_count.load();
  impl->bake_ms = total.ms();
  return RadianceField(std::move(impl));
}

namespace {

void put(float* out, std::size_t k, Rgb c) {
  out[3 * k] = c.r;
  out[3 * k + 1] = c.g;
  out[3 * k + 2] = c.b;
}

// Calls shade(k, p, d, s, t) for each pixel k whose camera ray crosses the window towards the
// field, in parallel over rows.
template <class Shade>
void for_each_window_pixel(const Frame& f, const Camera& camera, int threads,
                           std::vector<std::uint8_t>& covered, Shade&& shade) {
  const CameraRays cam(camera);
  covered.assign(std::size_t(camera.width) * std::size_t(camera.height), 0);
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] {
    parallel_for(camera.height, [&](int j) {
      for (int i = 0; i < camera.width; ++i) {
        const std::size_t k = std::size_t(j) * std::size_t(camera.width) + std::size_t(i);
        const Vec3 d = cam.direction(i, j);
        float s = 0, t = 0;
        Vec3 p;
        if (!f.crossing(cam.origin(), d, s, t, p)) continue;
        covered[k] = 1;
        shade(k, p, d, s, t);
      }
    });
  });
}

}  // namespace

namespace {

// The format's camera rules (check_camera), as a Status.
Status camera_ok(const Camera& c) {
  try {
    check_camera("camera", c);
  } catch (const io::JsonFailure& f) {
    return Error{f.message};
  }
  return {};
}

}  // namespace

Expected<FieldView> RadianceField::view(const Camera& camera, int threads) const {
  if (Status s = camera_ok(camera); !s) return s.error();
  if (threads < 0 || threads > 1024)
    return Error{"`threads`: expected 0..1024, found " + std::to_string(threads)};
  Stopwatch watch;
  FieldView v;
  v.radiance = ImageRgb(camera.width, camera.height);
  float* out = v.radiance.data();
  for_each_window_pixel(impl_->frame, camera, threads, v.covered,
                        [&](std::size_t k, Vec3, Vec3 d, float s, float t) {
                          put(out, k, impl_->radiance(s, t, d));
                        });
  v.time_ms = watch.ms();
  return v;
}

Rgb RadianceField::radiance(float s, float t, Vec3 towards) const {
  if (!std::isfinite(s + t) || !std::isfinite(towards.x + towards.y + towards.z)) return {};
  return impl_->radiance(std::clamp(s, 0.0f, 1.0f), std::clamp(t, 0.0f, 1.0f), towards);
}

const FieldOptions& RadianceField::options() const {
  return impl_->o;
}
int RadianceField::probes_u() const {
  return impl_->nu0;
}
int RadianceField::probes_v() const {
  return impl_->nv0;
}
std::vector<std::uint64_t> RadianceField::store_bytes() const {
  std::vector<std::uint64_t> out;
  for (const Cascade& k : impl_->c) out.push_back(cascade_bytes(k));
  return out;
}
std::vector<StageTime> RadianceField::stages() const {
  return impl_->stages;
}
double RadianceField::bake_ms() const {
  return impl_->bake_ms;
}
std::uint64_t RadianceField::memory_bytes() const {
  return impl_->memory;
}
std::uint64_t RadianceField::rays() const {
  return impl_->rays;
}

Expected<FieldView> reference_view(const Scene& in, const Window& window, const Camera& camera,
                                   int spp, int bounces, std::uint64_t seed, int threads,
                                   std::uint64_t max_memory) {
  FieldOptions o;
  o.window = window;
  o.bounces = bounces;
  o.spp = spp;
  o.threads = threads;
  if (Status s = check_field_options(o); !s) return s.error();
  if (Status s = check_scene(in); !s) return s.error();
  if (Status s = camera_ok(camera); !s) return s.error();
  Expected<int> k = light_exponent(in, bounces);
  if (!k) return k.error();
  const std::uint64_t pixels = std::uint64_t(camera.width) * std::uint64_t(camera.height);
  const std::uint64_t need =
      RayScene::estimate_bytes(in) + pixels * (sizeof(Rgb) + 2) + (*k > 0 ? scene_bytes(in) : 0);
  if (need > max_memory)
    return Error{"the reference view needs " + std::to_string(need >> 20) +
                 " MiB of working memory, over the limit of " + std::to_string(max_memory >> 20) +
                 " MiB"};
  Stopwatch watch;
  const Scene dim = *k > 0 ? dimmed(in, *k) : Scene{};
  const Scene& scene = *k > 0 ? dim : in;
  Expected<RayScene> rays = RayScene::build(scene, max_memory);
  if (!rays) return rays.error();
  const pt::SegmentTracer tracer(scene, *rays, bounces);
  const std::uint32_t base = sobol::hash(seed);
  const float scale = std::ldexp(1.0f, *k);
  std::atomic<std::uint64_t> ray_count{0};
  FieldView v;
  v.radiance = ImageRgb(camera.width, camera.height);
  float* out = v.radiance.data();
  v.sees_emitter.assign(std::size_t(camera.width) * std::size_t(camera.height), 0);
  for_each_window_pixel(
      Frame(window), camera, threads, v.covered, [&](std::size_t px, Vec3 p, Vec3 d, float, float) {
        Hit first;
        if (rays->intersect(Ray{p, d, 0, kInf}, first))
          v.sees_emitter[px] = !is_black(emission_at(scene, first));
        const std::uint32_t pixel_seed = sobol::hash((std::uint64_t(base) << 32) | px);
        std::vector<MediumPiece> pieces;
        std::uint64_t local = 0;
        double sum[3] = {0, 0, 0};
        for (int s = 0; s < spp; ++s) {
          const Rgb c =
              tracer.trace(p, d, kInf, 0, pixel_seed, std::uint32_t(s), pieces, local).radiance;
          if (!std::isfinite(c.r + c.g + c.b)) continue;
          sum[0] += c.r;
          sum[1] += c.g;
          sum[2] += c.b;
        }
        put(out, px, Rgb{float(sum[0] / spp), float(sum[1] / spp), float(sum[2] / spp)} * scale);
        ray_count.fetch_add(local, std::memory_order_relaxed);
      });
  v.time_ms = watch.ms();
  v.rays = ray_count.load();
  return v;
}

}  // namespace penumbra::spaceland
