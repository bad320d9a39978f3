// The 3D dispatcher: checks, the memory estimate, the ray tracer's scene, the G-buffer, the
// radiance cache where the method needs one, then the method's solve from the method table.
#include "penumbra/spaceland/render.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include "core/fnv.hpp"
#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/atlas/file.hpp"
#include "spaceland/atlas/render.hpp"
#include "spaceland/brightness.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/gbuffer.hpp"
#include "spaceland/method.hpp"
#include "spaceland/radiance_cache.hpp"
#include "spaceland/sky.hpp"
#include "spaceland/temporal.hpp"

namespace penumbra::spaceland {

namespace {

// The result image: 3 floats per pixel.
constexpr std::uint64_t kImageBytesPerPixel = 3 * sizeof(float);

bool known(Method m) {
  return int(m) >= 0 && std::size_t(m) < method_table().size();
}

// Later bounces from the radiance cache: a method that does not follow them, more than one.
bool needs_cache(const RenderOptions& o) {
  return known(o.method) && !entry(o.method).bounces_itself(o) && o.bounces > 1;
}

// The radiance cache's grid: the grid's defaults but its voxels, levels and probe spacing (the
// method's own cascade options, e.g. spwi's 64 directions, are not the cache's).
GridOptions cache_grid(const RenderOptions& o) {
  GridOptions g;
  g.voxel = o.grid.voxel;
  g.levels = o.grid.levels;
  g.probe_spacing = o.cache_probe_spacing;
  return g;
}

}  // namespace

std::vector<MethodInfo> methods() {
  std::vector<MethodInfo> list;
  for (const MethodEntry& e : method_table())
    list.push_back({e.method, e.name, e.title, e.summary,
                    std::vector<std::string>(e.options.begin(), e.options.end()),
                    e.gpu != nullptr});
  return list;
}

const char* to_string(Method m) {
  return known(m) ? entry(m).name : "?";
}

const char* to_string(Device d) {
  return d == Device::gpu ? "gpu" : "cpu";
}

const char* to_string(Aov a) {
  switch (a) {
    case Aov::radiance:
      return "radiance";
    case Aov::depth:
      return "depth";
    case Aov::normal:
      return "normal";
    case Aov::albedo:
      return "albedo";
    case Aov::position:
      return "position";
    case Aov::emission:
      return "emission";
    case Aov::object:
      return "object";
  }
  return "?";
}

const char* to_string(SpwiMerge m) {
  switch (m) {
    case SpwiMerge::bilinear:
      return "bilinear";
    case SpwiMerge::bilateral:
      return "bilateral";
    case SpwiMerge::bilinear3d:
      return "bilinear3d";
    case SpwiMerge::fix:
      return "fix";
    case SpwiMerge::minmax:
      return "minmax";
  }
  return "?";
}

const char* to_string(SpwiGather g) {
  return g == SpwiGather::pixel ? "pixel" : "probe";
}
const char* to_string(SsrcOffscreen o) {
  return o == SsrcOffscreen::sky ? "sky" : "world";
}
const char* to_string(SpecularQuery q) {
  return q == SpecularQuery::cone ? "cone" : q == SpecularQuery::wide ? "wide" : "ray";
}
const char* to_string(SpwiSun s) {
  return s == SpwiSun::direct ? "direct" : "cascades";
}

namespace {

// The method's parameters as used and its line, from its table entry (none for an unknown one).
struct Description {
  std::vector<Parameter> parameters;
  std::string line;
};
Description description(const RenderResult& result) {
  Description d;
  if (known(result.options.method))
    entry(result.options.method).describe(result, d.parameters, d.line);
  return d;
}

}  // namespace

std::vector<Parameter> describe(const RenderResult& result) {
  return description(result).parameters;
}

std::string describe_line(const RenderResult& result) {
  return description(result).line;
}

Status check_options(const RenderOptions& o) {
  // Fields are named as in RenderOptions; the command line shows its flags instead.
  if (o.bounces < 1 || o.bounces > 64)
    return Error{"`bounces`: expected 1..64, found " + std::to_string(o.bounces)};
  if (o.threads < 0 || o.threads > 1024)
    return Error{"`threads`: expected 0..1024, found " + std::to_string(o.threads)};
  if (!known(o.method)) return Error{"`method`: unknown method " + std::to_string(int(o.method))};
  const MethodEntry& m = entry(o.method);
  if (o.device == Device::gpu && !m.gpu)
    return Error{std::string("`device` gpu: ") + m.title + " (" + m.name +
                 ") runs on the CPU only (docs/GPU.md)"};
  // The method's own options (ranges and combinations) before any scene is read, then the
  // radiance cache's where the method takes its later bounces from it.
  if (m.check_options)
    if (Status s = m.check_options(o); !s) return s;
  if (o.temporal.frames < 0 || o.temporal.frames > 1024)
    return Error{"`temporal.frames`: expected 0..1024 frames (0: off), found " +
                 std::to_string(o.temporal.frames)};
  if (o.temporal.frames > 0 && o.method != Method::ssrc && o.method != Method::spwi)
    return Error{std::string("`temporal.frames`: temporal accumulation is ssrc's and spwi's "
                             "(their screen directions or probes moved each frame); ") +
                 m.title + " (" + m.name + ") draws the same image every frame"};
  if (o.temporal.grid_slabs < 0 || o.temporal.grid_slabs > (1 << 20))
    return Error{"`temporal.grid_slabs`: expected 0..1048576 slabs a frame (0: off), found " +
                 std::to_string(o.temporal.grid_slabs)};
  if (o.temporal.grid_slabs > 0 && o.method != Method::grid)
    return Error{std::string("`temporal.grid_slabs`: the grid's solve spread over frames; ") +
                 m.title + " (" + m.name + ") has no grid"};
  if (o.sun_rays < 1 || o.sun_rays > 1024)
    return Error{"`sun_rays`: expected 1..1024 shadow rays, found " + std::to_string(o.sun_rays)};
  if (!needs_cache(o)) return {};
  if (o.cache_probe_spacing < 1 || o.cache_probe_spacing > 64)
    return Error{"`cache_probe_spacing`: expected 1..64 voxels, found " +
                 std::to_string(o.cache_probe_spacing)};
  return RadianceCache::check_options(cache_grid(o));
}

Expected<Plan> make_plan(const Scene& scene, const RenderOptions& options) {
  if (Status s = check_options(options); !s) return s.error();
  if (Status s = check_scene(scene); !s) return s.error();
  const MethodEntry& m = entry(options.method);
  if (options.aov == Aov::radiance && m.check_scene)
    if (Status s = m.check_scene(scene); !s) return s.error();
  Plan plan;
  plan.options = options;
  plan.width = scene.camera.width;
  plan.height = scene.camera.height;
  plan.radiance_cache = options.aov == Aov::radiance && needs_cache(options);
  if (options.aov == Aov::radiance) {
    Expected<int> k = light_exponent(scene, options.bounces);
    if (!k) return k.error();
    plan.light_exponent = *k;
  }
  return plan;
}

Status check_brightness(const Scene& scene, const RenderOptions& options) {
  if (options.aov != Aov::radiance) return {};
  if (Expected<int> k = light_exponent(scene, options.bounces); !k) return k.error();
  return {};
}

std::uint64_t estimate_memory(const Scene& scene, const RenderOptions& options) {
  const std::uint64_t pixels = std::uint64_t(scene.camera.width) * scene.camera.height;
  const std::uint64_t per_pixel = GBuffer::bytes_per_pixel() + kImageBytesPerPixel;
  std::uint64_t method = 0;
  if (options.aov == Aov::radiance && known(options.method)) {
    method = entry(options.method).working_bytes(scene, options);
    if (needs_cache(options))
      method += RadianceCache::estimate_bytes(scene, cache_grid(options), options.max_memory);
  }
  // A scene brighter than the methods compute with is rendered from a dimmed copy.
  std::uint64_t copy = 0;
  if (options.aov == Aov::radiance)
    if (Expected<int> k = light_exponent(scene, options.bounces); k && *k > 0)
      copy = scene_bytes(scene);
  return RayScene::estimate_bytes(scene) + pixels * per_pixel + method + copy;
}

Status check_memory(const Scene& scene, const RenderOptions& options) {
  const std::uint64_t held = scene_bytes(scene);
  const std::uint64_t need = estimate_memory(scene, options) + held;
  if (need > options.max_memory)
    return Error{"needs about " + io::format_mib(need) + " of memory (the scene " +
                 io::format_mib(held) + ", the ray tracer's BVH and " +
                 std::to_string(scene.camera.width) + "x" + std::to_string(scene.camera.height) +
                 " pixels of buffers), more than the `" + "max_memory` limit of " +
                 io::format_mib(options.max_memory)};
  return {};
}

namespace {

// The method's image: the radiance cache first where it needs one, then its solve.
// `room`: the memory limit less what is held already (the scene, the BVH, the pixel buffers),
// which the method's own refusals (the grid's cascades, the radiance cache) are held to.
// With `exact`, temporal accumulation's frame `frame`: its index passed on, and what
// the method reports for it (SolveReport::exact) returned there.
Status solve(const Plan& plan, const Scene& scene, const Scene& given, const RayScene& rays,
             const GBuffer& g, std::uint64_t room, Kept* kept, std::uint64_t frame,
             temporal::Exact* exact, RenderResult& result) {
  const RenderOptions& o = plan.options;
  const MethodEntry& m = entry(o.method);
  SolveContext ctx{scene, rays, g, o.bounces, room, o.sun_rays};
  ctx.given = &given;
  ctx.light_exponent = plan.light_exponent;
  ctx.progress = &o.progress;
  ctx.cancel = o.cancel;
  ctx.kept = kept;
  ctx.frame = frame;
  ctx.want_exact = exact != nullptr;
  ctx.grid_slabs = kept ? std::uint64_t(o.temporal.grid_slabs) : 0;
  std::optional<RadianceCache> cache;
  if (plan.radiance_cache) {
    Stopwatch watch;
    Expected<RadianceCache> built =
        RadianceCache::build(scene, rays, cache_grid(o), room, o.bounces - 1, focus_distance(g));
    if (!built) return built.error();
    cache = std::move(*built);
    ctx.cache = &*cache;
    result.memory_bytes += cache->bytes();
    result.stages.push_back({"radiance cache", watch.ms()});
  }
  SolveReport report;
  RenderOptions used = o;
  if (cache) {
    used.grid.voxel = cache->voxel();
    used.grid.levels = cache->levels();
  }
  Expected<ImageRgb> img = (o.device == Device::gpu ? m.gpu : m.cpu)(ctx, o, report, used);
  if (!img) return img.error();
  result.radiance = std::move(*img);
  if (exact) *exact = std::move(report.exact);
  for (StageTime& st : report.stages) result.stages.push_back(std::move(st));
  result.rays += report.rays;
  result.samples = report.samples;
  result.cancelled = report.cancelled;
  for (std::string& w : report.warnings) result.warnings.push_back(std::move(w));
  result.memory_bytes += report.memory_bytes;
  result.voxel_bytes = report.voxel_bytes;
  result.grid_slabs_done = report.grid_slabs_done;
  result.grid_slabs = report.grid_slabs;
  result.options = used;
  return {};
}

// Only a miss's depth may be infinite.
Status check_finite(const ImageRgb& image, Aov aov) {
  const float* p = image.data();
  for (std::size_t i = 0; i < image.size(); ++i) {
    if (std::isfinite(p[i])) continue;
    if (aov == Aov::depth && std::isinf(p[i]) && p[i] > 0) continue;
    const std::size_t px = i / 3;
    return Error{"the result is not finite at pixel (" + std::to_string(px % image.width()) + ", " +
                 std::to_string(px / image.width()) + "): a bug; please report it with the scene"};
  }
  return {};
}

}  // namespace

struct Renderer::State {
  std::uint64_t scene_key = 0;
  std::optional<RayScene> rays;
  Kept kept;
  Method method = Method::pt;  // whose state `kept` holds
  temporal::History history;   // RenderOptions::temporal's
};

namespace {

// The scene but its camera (and names): what the BVH and a method's kept state are made from;
// `geometry` without its sky and sun.
std::uint64_t scene_key(const Scene& scene, std::uint64_t& geometry) {
  Fnv1a f;
  f.value(atlas::scene_hash(scene, false));  // geometry, materials, textures
  // Which object each shape belongs to (the BVH reports it: the object AOV, ssrc's back faces).
  for (const TriangleMesh& m : scene.meshes) f.value(m.object);
  for (const Sphere& sp : scene.spheres) f.value(sp.object);
  for (const Disk& d : scene.disks) f.value(d.object);
  for (const Medium& m : scene.media) {
    f.value(m.center);
    f.value(m.half_size);
    f.value(m.axes);
    f.value(m.extinction);
    f.value(m.albedo);
    f.value(m.emission);
  }
  geometry = f.h;
  hash_light(f, scene);
  return f.h;
}

// The state's BVH for `scene`: kept where the scene but its camera is the same, else built
// (dropping the method's state too, unless `keep_method`: a method that checks its state against
// the scene itself). Sets `built` when it was built.
Status keep_rays(const Scene& scene, std::uint64_t max_memory, Renderer::State& state, bool& built,
                 bool keep_method = false) {
  std::uint64_t geometry = 0;
  const std::uint64_t key = scene_key(scene, geometry);
  built = false;
  state.kept.geometry_key = geometry;
  if (key != state.scene_key || !state.rays) {
    state.rays.reset();
    state.kept.scene_key = key;
    if (!keep_method) state.kept.method.reset();
    state.scene_key = key;
    Expected<RayScene> r = RayScene::build(scene, max_memory);
    if (!r) {
      state.scene_key = 0;
      return r.error();
    }
    state.rays = std::move(*r);
    built = true;
  }
  return {};
}

// render(), keeping the BVH and the method's state in `state` where given.
Expected<RenderResult> render_kept(const Scene& scene, const RenderOptions& options,
                                   Renderer::State* state) {
  Expected<Plan> plan = make_plan(scene, options);
  if (!plan) return plan.error();
  if (Status s = check_memory(scene, options); !s) return s.error();

  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  return arena.execute([&]() -> Expected<RenderResult> {
    RenderResult result;
    result.options = options;
    result.device = to_string(options.device);
    result.warnings = scene.warnings;  // what its files use and it is drawn without
    Stopwatch total;
    Stopwatch stage;
    // Embree may not allocate past the limit (its estimate was checked above; this holds it).
    std::optional<RayScene> built;
    const bool temporal = state && options.temporal.frames > 0 && options.aov == Aov::radiance;
    std::uint64_t frame = 0;
    if (state) {
      const std::uint64_t before = state->scene_key;
      bool fresh = false;
      // The grid keys its grids by the scene itself: a changed sun or sky solves over the last
      // grid's voxels, and with temporal.grid_slabs shows that grid until the new one is solved.
      const bool grid = options.method == Method::grid;
      if (Status s = keep_rays(scene, options.max_memory, *state, fresh, grid); !s)
        return s.error();
      // The history goes with another method or options, and with a scene that changed in more
      // than its camera, sun and sky (a moved light is followed: the old light fades in frames).
      temporal::History& h = state->history;
      const temporal::Made made{options.method,
                                options.device,
                                options.bounces,
                                options.sun_rays,
                                options.cache_probe_spacing,
                                options.temporal.frames,
                                options.ssrc,
                                options.spwi};
      // So does a new image size: its first frame at a new resolution would take the old one's
      // blur for frames (the viewer's still camera switching to full resolution).
      if (!temporal || h.made != made || h.camera.width != scene.camera.width ||
          h.camera.height != scene.camera.height ||
          (state->scene_key != before && h.sun == scene.sun && h.sky == scene.sky))
        h.clear();
      if (temporal) {
        h.made = made;
        frame = h.frame;
      }
      if (fresh) result.stages.push_back({"build BVH", stage.ms()});
    } else {
      Expected<RayScene> r = RayScene::build(scene, options.max_memory);
      if (!r) return r.error();
      built = std::move(*r);
      result.stages.push_back({"build BVH", stage.ms()});
    }
    stage.restart();
    const RayScene* rays = built ? &*built : &*state->rays;
    const GBuffer g = make_gbuffer(scene, *rays);
    result.stages.push_back({"G-buffer", stage.ms()});
    stage.restart();
    result.memory_bytes =
        rays->bytes() + plan->pixels() * (GBuffer::bytes_per_pixel() + kImageBytesPerPixel);
    result.rays = plan->pixels();  // the G-buffer's camera rays
    if (options.aov != Aov::radiance) {
      result.radiance = aov_image(scene, g, options.aov);
      result.stages.push_back({"AOV", stage.ms()});
    } else {
      // Bright light at 2^-k, scaled back: exact, as powers of two move exponents only.
      const int k = plan->light_exponent;
      const Scene lit = k ? dimmed(scene, k) : Scene{};
      const std::uint64_t held =
          result.memory_bytes + scene_bytes(scene) * (k ? 2 : 1);  // the copy, where dimmed
      const std::uint64_t room = options.max_memory - std::min(options.max_memory, held);
      // One method's state at a time: another method's is dropped before this one runs, so
      // that the memory it held is not held beside this one's.
      if (state && state->method != options.method) {
        state->kept.method.reset();
        state->method = options.method;
      }
      temporal::Exact exact;
      if (Status s =
              solve(*plan, k ? lit : scene, scene, *rays, g, room, state ? &state->kept : nullptr,
                    frame, temporal ? &exact : nullptr, result);
          !s)
        return s.error();
      if (k) {
        float* p = result.radiance.data();
        for (std::size_t i = 0; i < result.radiance.size(); ++i) {
          const float v = std::ldexp(p[i], k);
          // An estimate past the bound (the path tracer's samples scatter about the answer)
          // where the answer is close to the float range: refused, not written as infinite.
          if (std::isfinite(p[i]) && !std::isfinite(v)) {
            const std::size_t px = i / 3;
            return Error{std::string(entry(options.method).title) + "'s estimate at pixel (" +
                         std::to_string(px % result.radiance.width()) + ", " +
                         std::to_string(px / result.radiance.width()) +
                         ") passes the float range (3.4e+38): the scene's light is too close to "
                         "it for the estimate's spread; scale the scene's emission, sky and sun "
                         "down"};
          }
          p[i] = v;
        }
      }
      if (temporal) {
        stage.restart();
        temporal::History& h = state->history;
        result.temporal_frame = h.frame;
        if (k)
          for (Rgb& c : exact.light)
            c = {std::ldexp(c.r, k), std::ldexp(c.g, k), std::ldexp(c.b, k)};
        temporal::accumulate(scene, g, exact, options.temporal.frames, result.radiance, h);
        result.memory_bytes += h.bytes();
        result.stages.push_back({"temporal", stage.ms()});
      }
    }
    result.time_ms = total.ms();
    if (Status s = check_finite(result.radiance, options.aov); !s) return s.error();
    return result;
  });
}

}  // namespace

Expected<RenderResult> render(const Scene& scene, const RenderOptions& options) {
  return render_kept(scene, options, nullptr);
}

Renderer::Renderer() : state_(std::make_unique<State>()) {}
Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;

Expected<RenderResult> Renderer::render(const Scene& scene, const RenderOptions& options) {
  if (!state_) state_ = std::make_unique<State>();  // a moved-from renderer works again
  return render_kept(scene, options, state_.get());
}

Expected<std::vector<ImageRgb>> Renderer::channels(const Scene& scene, const std::vector<Aov>& aovs,
                                                   const RenderOptions& options) {
  for (Aov a : aovs)
    if (a == Aov::radiance) return Error{"Renderer::channels: radiance is not a G-buffer channel"};
  if (Status s = check_scene(scene); !s) return s.error();
  RenderOptions o;
  o.aov = Aov::depth;  // the BVH and the G-buffer
  o.max_memory = options.max_memory;
  if (Status s = check_memory(scene, o); !s) return s.error();
  if (!state_) state_ = std::make_unique<State>();
  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  return arena.execute([&]() -> Expected<std::vector<ImageRgb>> {
    bool built = false;
    if (Status s = keep_rays(scene, o.max_memory, *state_, built); !s) return s.error();
    const GBuffer g = make_gbuffer(scene, *state_->rays);
    std::vector<ImageRgb> out;
    for (Aov a : aovs) out.push_back(aov_image(scene, g, a));
    return out;
  });
}

void Renderer::clear() {
  state_ = std::make_unique<State>();
}

Expected<BakeResult> bake(const Scene& scene, const RenderOptions& options, const std::string& path,
                          bool radiance) {
  RenderOptions o = options;
  o.method = Method::surface;
  o.aov = Aov::radiance;
  if (!o.surface.atlas.empty())
    return Error{"`surface.atlas`: a bake makes an atlas; it reads none (found \"" +
                 o.surface.atlas + "\")"};
  Expected<Plan> plan = make_plan(scene, o);
  if (!plan) return plan.error();
  // The BVH and the bake; no camera image.
  const std::uint64_t held = scene_bytes(scene) * (plan->light_exponent ? 2 : 1);
  const std::uint64_t need =
      held + RayScene::estimate_bytes(scene) + atlas::working_bytes(scene, o.surface, radiance);
  if (need > o.max_memory)
    return Error{"the bake needs about " + io::format_mib(need) +
                 " of memory (the scene, the ray tracer's BVH, the atlas's cascades" +
                 (radiance ? std::string(" and its radiance per direction") : "") +
                 "), more than the `max_memory` limit of " + io::format_mib(o.max_memory) +
                 "; use fewer texels"};
  tbb::task_arena arena(o.threads > 0 ? o.threads : tbb::task_arena::automatic);
  return arena.execute([&]() -> Expected<BakeResult> {
    Stopwatch total, stage;
    BakeResult result;
    Expected<RayScene> rays = RayScene::build(scene, o.max_memory);
    if (!rays) return rays.error();
    result.stages.push_back({"build BVH", stage.ms()});
    const int k = plan->light_exponent;
    const Scene lit = k ? dimmed(scene, k) : Scene{};
    const std::uint64_t used = rays->bytes() + scene_bytes(scene) * (k ? 2 : 1);
    atlas::FileBake fb{k ? lit : scene, scene, *rays, o.surface, o.bounces, k, radiance};
    fb.max_bytes = o.max_memory - std::min(o.max_memory, used);
    if (Status s = atlas::bake_file(fb, path, result); !s) return s.error();
    result.memory_bytes += rays->bytes();
    result.time_ms = total.ms();
    return result;
  });
}

}  // namespace penumbra::spaceland
