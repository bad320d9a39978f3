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
#include "spaceland/pt/pt.hpp"

namespace penumbra::spaceland {

namespace {

// The method table: name, help, and the working memory per pixel besides the G-buffer.
struct MethodEntry {
  MethodInfo info;
  std::uint64_t bytes_per_pixel;
};

const MethodEntry kMethods[] = {
    {{Method::pt, "pt",
      "reference path tracer (next event estimation + MIS, fog, Owen-scrambled Sobol points)"},
     pt::kBytesPerPixel},
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
  return {};
}

std::uint64_t estimate_memory(const Scene& scene, const RenderOptions& options) {
  const std::uint64_t pixels = std::uint64_t(scene.camera.width) * scene.camera.height;
  std::uint64_t per_pixel = GBuffer::bytes_per_pixel() + 3 * sizeof(float);  // + the image
  if (options.aov == Aov::radiance) per_pixel += entry(options.method).bytes_per_pixel;
  return RayScene::estimate_bytes(scene) + pixels * per_pixel;
}

Status check_memory(const Scene& scene, const RenderOptions& options) {
  const std::uint64_t need = estimate_memory(scene, options) + scene_bytes(scene);
  if (need > options.max_memory)
    return Error{"needs about " + mib(need) + " of memory (the scene " + mib(scene_bytes(scene)) +
                 ", the ray tracer's BVH and " + std::to_string(scene.camera.width) + "x" +
                 std::to_string(scene.camera.height) + " pixels of buffers), more than the `" +
                 "max_memory` limit of " + mib(options.max_memory)};
  return {};
}

Expected<RenderResult> render(const Scene& scene, const RenderOptions& options) {
  if (Status s = check_options(options); !s) return s.error();
  if (Status s = check_scene(scene); !s) return s.error();
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
    result.memory_bytes = rays->bytes() + pixels * (GBuffer::bytes_per_pixel() + 12);
    if (options.aov != Aov::radiance) {
      result.radiance = aov_image(scene, g, options.aov);
      result.stages.push_back({"AOV", stage.ms()});
      result.rays = pixels;
    } else {
      pt::Stats stats;
      result.radiance = pt::render(scene, *rays, g, options, stats);
      result.stages.push_back({"path trace", stage.ms()});
      result.rays = stats.rays;
      result.samples = stats.samples;
      result.cancelled = stats.cancelled;
      result.memory_bytes += pixels * pt::kBytesPerPixel;
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
