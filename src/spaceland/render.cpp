// The 3D dispatcher: checks, the memory estimate, the ray tracer's scene, the G-buffer, then the
// method from the method table.
#include "penumbra/spaceland/render.hpp"

#include <tbb/task_arena.h>

#include <cmath>
#include <string>

#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/gbuffer.hpp"
#include "spaceland/grid/grid.hpp"
#include "spaceland/grid/voxels.hpp"
#include "spaceland/pt/pt.hpp"
#include "spaceland/spwi/spwi.hpp"

namespace penumbra::spaceland {

namespace {

// The result image: 3 floats per pixel.
constexpr std::uint64_t kImageBytesPerPixel = 3 * sizeof(float);

std::uint64_t pt_bytes(const Scene& scene, const RenderOptions&) {
  return std::uint64_t(scene.camera.width) * scene.camera.height * pt::kBytesPerPixel;
}

// What a method's solver is handed, and what it gives back besides the image.
struct Solved {
  std::vector<StageTime> stages;
  std::uint64_t rays = 0, samples = 0, memory_bytes = 0, voxel_bytes = 0;
  bool cancelled = false;
  RenderOptions derived;  // the options with the values the method derived filled in
};
using Solve = Expected<ImageRgb> (*)(const Scene&, const RayScene&, const GBuffer&,
                                     const RenderOptions&, Solved&);

Expected<ImageRgb> pt_solve(const Scene& scene, const RayScene& rays, const GBuffer& g,
                            const RenderOptions& options, Solved& out) {
  pt::Stats stats;
  Stopwatch watch;
  ImageRgb img = pt::render(scene, rays, g, options, stats);
  out.stages.push_back({"path trace", watch.ms()});
  out.rays = stats.rays;
  out.samples = stats.samples;
  out.cancelled = stats.cancelled;
  out.memory_bytes = pt_bytes(scene, options);
  return img;
}

// What every method's stats report alike.
template <class Stats>
void take_common(Stats& stats, Solved& out) {
  out.stages = std::move(stats.stages);
  out.rays = stats.rays;
  out.memory_bytes = stats.memory_bytes;
}

Expected<ImageRgb> spwi_solve(const Scene& scene, const RayScene& rays, const GBuffer& g,
                              const RenderOptions& options, Solved& out) {
  spwi::Stats stats;
  Expected<ImageRgb> img = spwi::render(scene, rays, g, options, stats);
  take_common(stats, out);
  out.derived.spwi.interval = stats.plan.t0;
  out.derived.spwi.cascades = stats.plan.cascades;
  return img;
}

Expected<ImageRgb> grid_solve(const Scene& scene, const RayScene& rays, const GBuffer& g,
                              const RenderOptions& options, Solved& out) {
  grid::Stats stats;
  Expected<ImageRgb> img = grid::render(scene, rays, g, options, stats);
  take_common(stats, out);
  out.derived.grid.voxel = stats.voxel;
  out.derived.grid.interval = stats.t0;
  out.derived.grid.cascades = stats.cascades;
  out.voxel_bytes = stats.voxel_bytes;
  return img;
}

// The voxels; the cascades' share is checked when they are planned (the grid's size is known
// only once the voxel size is).
std::uint64_t grid_bytes(const Scene& scene, const RenderOptions& options) {
  const std::array<double, 3> d =
      grid::grid_dims(grid::grid_bounds(scene), grid::voxel_size(scene, options));
  return std::uint64_t(
      std::min(d[0] * d[1] * d[2] * double(grid::voxel_bytes(1, options.bounces > 1)), 1.8e19));
}

Status no_check(const Scene&, const RenderOptions&) {
  return {};
}

// Its later bounces come from the probe grid's radiance cache: its voxels too.
std::uint64_t spwi_bytes(const Scene& scene, const RenderOptions& options) {
  return spwi::bytes_upper_bound(scene.camera.width, scene.camera.height, options.spwi) +
         (options.bounces > 1 ? grid_bytes(scene, options) : 0);
}

// The method table (docs/ARCHITECTURE.md): name, help, the method's own option check, its
// working memory besides the G-buffer (known before anything is allocated), its solver.
struct MethodEntry {
  MethodInfo info;
  Status (*check)(const Scene&, const RenderOptions&);
  std::uint64_t (*bytes)(const Scene&, const RenderOptions&);
  Solve solve;
};

const MethodEntry kMethods[] = {
    {{Method::pt, "pt",
      "reference path tracer (next event estimation + MIS, fog, Owen-scrambled Sobol points)"},
     no_check,
     pt_bytes,
     pt_solve},
    {{Method::spwi, "spwi",
      "screen-space probes with world-space intervals (seed 000): radiance cascades on the "
      "G-buffer, later bounces from the probe grid's radiance cache"},
     spwi::check,
     spwi_bytes,
     spwi_solve},
    {{Method::grid, "grid",
      "the world-space probe grid (seed 001 4.3): radiance cascades over the scene's voxels, "
      "fog and light shafts, later bounces, the radiance cache spwi's come from"},
     no_check,  // check_options checks the grid's options; any scene will do
     grid_bytes,
     grid_solve},
};

const MethodEntry& entry(Method m) {
  for (const MethodEntry& e : kMethods)
    if (e.info.method == m) return e;
  return kMethods[0];
}

std::string mib(std::uint64_t bytes) {
  return io::format_rounded(double(bytes) / double(1 << 20)) + " MiB";
}

}  // namespace

std::vector<MethodInfo> methods() {
  std::vector<MethodInfo> list;
  for (const MethodEntry& e : kMethods) list.push_back(e.info);
  return list;
}

const char* to_string(Method m) {
  return entry(m).info.name;
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
const char* to_string(SpwiSun s) {
  return s == SpwiSun::direct ? "direct" : "cascades";
}

Status check_options(const RenderOptions& o) {
  // Fields are named as in RenderOptions; the command line shows its flags instead.
  if (o.bounces < 1 || o.bounces > 64)
    return Error{"`bounces`: expected 1..64, found " + std::to_string(o.bounces)};
  if (o.threads < 0 || o.threads > 1024)
    return Error{"`threads`: expected 0..1024, found " + std::to_string(o.threads)};
  if (o.method == Method::pt) {
    if (o.pt.spp < 0)
      return Error{"`pt.spp`: expected a count >= 0, found " + std::to_string(o.pt.spp)};
    if (!std::isfinite(o.pt.seconds) || o.pt.seconds < 0)
      return Error{"`pt.seconds`: expected a number of seconds >= 0, found " +
                   io::format_number(o.pt.seconds)};
    if (o.pt.spp == 0 && o.pt.seconds == 0)
      return Error{
          "`pt.spp` is 0 (no limit) and no `pt.seconds` is given: the render would "
          "never end"};
  }
  // Each method's options (ranges and combinations) before any scene is read: SPWI's, the
  // grid's own, and the grid's for SPWI's later bounces, which come from its radiance cache.
  if (o.method == Method::spwi)
    if (Status s = spwi::check_options(o.spwi); !s) return s;
  if (o.method == Method::grid || (o.method == Method::spwi && o.bounces > 1))
    return grid::check_options(o.grid);
  return {};
}

std::uint64_t estimate_memory(const Scene& scene, const RenderOptions& options) {
  const std::uint64_t pixels = std::uint64_t(scene.camera.width) * scene.camera.height;
  const std::uint64_t per_pixel = GBuffer::bytes_per_pixel() + kImageBytesPerPixel;
  const std::uint64_t method =
      options.aov == Aov::radiance ? entry(options.method).bytes(scene, options) : 0;
  return RayScene::estimate_bytes(scene) + pixels * per_pixel + method;
}

Status check_memory(const Scene& scene, const RenderOptions& options) {
  const std::uint64_t held = scene_bytes(scene);
  const std::uint64_t need = estimate_memory(scene, options) + held;
  if (need > options.max_memory)
    return Error{"needs about " + mib(need) + " of memory (the scene " + mib(held) +
                 ", the ray tracer's BVH and " + std::to_string(scene.camera.width) + "x" +
                 std::to_string(scene.camera.height) + " pixels of buffers), more than the `" +
                 "max_memory` limit of " + mib(options.max_memory)};
  return {};
}

Expected<RenderResult> render(const Scene& scene, const RenderOptions& options) {
  if (Status s = check_options(options); !s) return s.error();
  if (Status s = check_scene(scene); !s) return s.error();
  if (options.aov == Aov::radiance)
    if (Status s = entry(options.method).check(scene, options); !s) return s.error();
  if (Status s = check_memory(scene, options); !s) return s.error();

  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  return arena.execute([&]() -> Expected<RenderResult> {
    RenderResult result;
    result.options = options;
    Stopwatch total;
    Stopwatch stage;
    // Embree may not allocate past the limit (its estimate was checked above; this holds it).
    Expected<RayScene> rays = RayScene::build(scene, options.max_memory);
    if (!rays) return rays.error();
    result.stages.push_back({"build BVH", stage.ms()});
    stage.restart();
    const GBuffer g = make_gbuffer(scene, *rays);
    result.stages.push_back({"G-buffer", stage.ms()});
    stage.restart();
    const std::uint64_t pixels = std::uint64_t(g.width) * g.height;
    result.memory_bytes =
        rays->bytes() + pixels * (GBuffer::bytes_per_pixel() + kImageBytesPerPixel);
    result.rays = pixels;  // the G-buffer's camera rays
    if (options.aov != Aov::radiance) {
      result.radiance = aov_image(scene, g, options.aov);
      result.stages.push_back({"AOV", stage.ms()});
    } else {
      Solved solved;
      solved.derived = options;
      Expected<ImageRgb> img = entry(options.method).solve(scene, *rays, g, options, solved);
      if (!img) return img.error();
      result.radiance = std::move(*img);
      for (StageTime& st : solved.stages) result.stages.push_back(std::move(st));
      result.rays += solved.rays;
      result.samples = solved.samples;
      result.cancelled = solved.cancelled;
      result.memory_bytes += solved.memory_bytes;
      result.voxel_bytes = solved.voxel_bytes;
      result.options = solved.derived;
    }
    result.time_ms = total.ms();
    // Only a miss's depth may be infinite.
    const float* p = result.radiance.data();
    for (std::size_t i = 0; i < result.radiance.size(); ++i) {
      if (std::isfinite(p[i])) continue;
      if (options.aov == Aov::depth && std::isinf(p[i]) && p[i] > 0) continue;
      const std::size_t px = i / 3;
      return Error{"the result is not finite at pixel (" + std::to_string(px % g.width) + ", " +
                   std::to_string(px / g.width) + "): a bug; please report it with the scene"};
    }
    return result;
  });
}

}  // namespace penumbra::spaceland
