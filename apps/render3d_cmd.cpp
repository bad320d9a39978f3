// `penumbra render` on a 3D scene: load it (meshes included), render the camera's image with one
// method, write the images, and report timings (a table, or JSON).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "penumbra/penumbra.hpp"
#include "progress.hpp"
#include "render_cmd.hpp"
#include "render_options.hpp"

namespace {

constexpr int kUsage = 2;
constexpr int kFailure = 1;
constexpr int kInterrupted = 130;

namespace sl = penumbra::spaceland;

// What every 3D render reads besides k3dOptions.
constexpr std::string_view kCommon[] = {"scene",     "--output",        "--method",   "--bounces",
                                        "--threads", "--max-memory",    "--exposure", "--json",
                                        "--quiet",   "--exposure-from", "--device"};

}  // namespace

namespace {

// Whether `method` reads the option named `flag` (its MethodInfo's fields, by their flags).
bool reads(const sl::MethodInfo& method, const std::string& flag) {
  for (const std::string& field : method.options)
    for (const std::string& f : flags_of(field))
      if (f == flag) return true;
  return false;
}

// An option given that the chosen method does not read: refused, naming the 3D methods that read
// it (or the 2D world); 0 when every option given is read.
int check_method_options(const RenderArgs& a, sl::Method method) {
  if (!a.app) return 0;
  for (const CLI::Option* opt : a.app->get_options()) {
    const std::string name = opt->get_name();
    if (opt->count() == 0 || listed(name, kCommon) || listed(name, k3dOptions)) continue;
    std::vector<std::string> names;
    bool read = false;
    for (const sl::MethodInfo& m : sl::methods())
      if (reads(m, name)) {
        names.push_back(m.name);
        read = read || m.method == method;
      }
    // "--method spwi", "--method spwi or grid", "--method spwi, grid or ssrc".
    std::string readers;
    for (std::size_t k = 0; k < names.size(); ++k)
      readers += (k == 0 ? "--method " : k + 1 == names.size() ? " or " : ", ") + names[k];
    if (readers.empty()) {
      std::cerr << "penumbra render: " << name << " applies to 2D scenes only (" << a.scene
                << " is a 3D scene)\n";
      return kUsage;
    }
    if (!read) {
      std::cerr << "penumbra render: " << name << " applies to " << readers << " only, not "
                << sl::to_string(method) << "\n";
      return kUsage;
    }
  }
  return 0;
}

}  // namespace

bool read_by_3d_method(const std::string& flag) {
  for (const sl::MethodInfo& m : sl::methods())
    if (reads(m, flag)) return true;
  return false;
}

int render_scene_3d(const RenderArgs& a) {
  sl::RenderOptions options;
  options.device =
      a.options.device == penumbra::flatland::Device::gpu ? sl::Device::gpu : sl::Device::cpu;
  if (!a.method.empty()) {
    bool known = false;
    for (const sl::MethodInfo& m : sl::methods())
      if (a.method == m.name) {
        options.method = m.method;
        known = true;
      }
    if (!known) {
      std::cerr << "penumbra render: --method " << a.method << " is a 2D method (" << a.scene
                << " is a 3D scene); 3D methods:";
      for (const sl::MethodInfo& m : sl::methods()) std::cerr << " " << m.name;
      std::cerr << "\n";
      return kUsage;
    }
  }
  if (int code = check_method_options(a, options.method); code != 0) return code;
  // spwi and grid: their defaults, and the options they share with 2D's cascades where given.
  auto given = [&](const char* name) { return a.app && a.app->get_option(name)->count() > 0; };
  auto cascade_options = [&](auto& m) {
    if (given("--probe-spacing")) m.probe_spacing = a.options.rc.probe_spacing;
    if (given("--directions")) m.directions = a.options.rc.directions;
    if (given("--interval")) m.interval = a.options.rc.interval;
    if (given("--cascades")) m.cascades = a.options.rc.cascades;
  };
  options.spwi = a.spwi;
  if (a.disjoint) options.spwi.overlap = false;
  cascade_options(options.spwi);
  if (given("--branching")) options.spwi.branching = a.options.rc.branching;
  if (given("--preaverage")) options.spwi.preaverage = a.options.rc.preaverage;
  options.grid = a.grid;
  cascade_options(options.grid);
  options.ssrc = a.ssrc;
  if (given("--probe-spacing")) options.ssrc.probe_spacing = a.options.rc.probe_spacing;
  if (given("--directions")) options.ssrc.directions = a.options.rc.directions;
  if (given("--cascades")) options.ssrc.cascades = a.options.rc.cascades;
  if (given("--interval") && options.method == sl::Method::ssrc) {
    // Pixels along the screen, a whole number (spwi's and the grid's are world units).
    const float r0 = a.options.rc.interval;
    if (r0 != std::floor(r0) || r0 < 1 || r0 > 4096) {
      std::cerr << "penumbra render: --interval for ssrc is a whole number of pixels in "
                   "1..4096, found "
                << r0 << "\n";
      return kUsage;
    }
    options.ssrc.interval = int(r0);
  }
  options.surface = a.surface;
  if (given("--directions")) options.surface.directions = a.options.rc.directions;
  if (given("--interval")) options.surface.interval = a.options.rc.interval;
  if (given("--cascades")) options.surface.cascades = a.options.rc.cascades;
  if (given("--merge")) options.ssrc.merge = a.spwi.merge;
  if (given("--gather")) options.ssrc.gather = a.spwi.gather;
  if (given("--specular")) {
    options.grid.specular = a.spwi.specular;
    options.ssrc.specular = a.spwi.specular;
    options.surface.specular = a.spwi.specular;
  }
  if (given("--merge-edge")) options.ssrc.merge_edge = a.spwi.merge_edge;
  if (given("--gather-edge")) options.ssrc.gather_edge = a.spwi.gather_edge;
  if (given("--gather-normal")) options.ssrc.gather_normal = a.spwi.gather_normal;
  options.cache_probe_spacing = a.cache_probe_spacing;
  options.sun_rays = a.sun_rays;
  // Extension on with --extend, tracing --extend-length voxels (cells in 2D); the fix off unless
  // --fix bilinear (2D's default is on: there every merge takes it).
  if (given("--extend") || given("--extend-length"))
    options.grid.extend_length = a.options.rc.extend_length;
  if (given("--fix")) {
    if (a.options.rc.fix == penumbra::flatland::MergeFix::nearest) {
      std::cerr << "penumbra render: --fix nearest applies to 2D scenes only; the 3D grid takes "
                   "--fix bilinear or none\n";
      return kUsage;
    }
    options.grid.fix = a.options.rc.fix == penumbra::flatland::MergeFix::bilinear;
  }
  // Named here by the flags given: the library's message names `grid.extend_length` alone (only
  // the grid reads both: another method has refused them above).
  if (options.grid.fix && options.grid.extend_length > 0) {
    std::cerr << "penumbra render: " << (given("--extend") ? "--extend" : "--extend-length")
              << " and --fix bilinear do not combine: extension doubles a probe's own intervals, "
                 "which the bilinear fix does not use (it traces to the upper probes instead); "
                 "use one or the other\n";
    return kUsage;
  }
  options.aov = a.aov;
  // The shared options, with --time alone meaning no sample limit, as in 2D.
  penumbra::flatland::RenderOptions shared = a.options;
  finish_render_options(shared, a.flags);
  options.pt.spp = shared.pt.spp;
  options.pt.seconds = shared.pt.seconds;
  options.pt.seed = shared.pt.seed;
  options.bounces = shared.bounces;
  options.threads = shared.threads;
  if (int code = check_render_args(a, options.max_memory); code != 0) return code;
  std::optional<penumbra::ImageRgb> metered;
  if (int code = read_exposure_source(a, metered); code != 0) return code;
  if (penumbra::Status s = sl::check_options(options); !s) {
    std::cerr << "penumbra render: " << with_flags(s.error().message) << "\n";
    return kUsage;
  }

  penumbra::Stopwatch load_watch;
  penumbra::Expected<sl::Scene> scene = sl::load_scene(a.scene, {options.max_memory});
  if (!scene) {
    std::cerr << "penumbra render: " << with_flags(scene.error().message) << "\n";
    return kFailure;
  }
  const double load_ms = load_watch.ms();
  // --width and --height replace the camera's image size; fov_y stays.
  if (a.width > 0) scene->camera.width = a.width;
  if (a.height > 0) scene->camera.height = a.height;
  if (penumbra::Status s = sl::check_memory(*scene, options); !s) {
    std::cerr << "penumbra render: " << a.scene << ": " << with_flags(s.error().message) << "\n";
    return kFailure;
  }
  // Its message names the file and the brightest value's path.
  if (penumbra::Status s = sl::check_brightness(*scene, options); !s) {
    std::cerr << "penumbra render: " << s.error().message << "\n";
    return kFailure;
  }

  const bool progress = !a.quiet && isatty(STDERR_FILENO) && options.aov == sl::Aov::radiance;
  if (progress) options.progress = draw_progress;
  // Only the path tracer has something to show when stopped early: Ctrl-C stops it after the
  // pass and it writes what it has, finishing the files even if Ctrl-C comes while they are
  // written. The other methods have nothing whole before they finish: Ctrl-C ends them at once,
  // writing nothing.
  const bool progressive = options.method == sl::Method::pt && options.aov == sl::Aov::radiance;
  if (progressive) {
    options.cancel = &g_cancel;
    watch_interrupts(true);
  }
  penumbra::Expected<sl::RenderResult> result = sl::render(*scene, options);
  if (progress) std::fprintf(stderr, "\n");
  if (!result) {
    std::cerr << "penumbra render: " << a.scene << ": " << with_flags(result.error().message)
              << "\n";
    return kFailure;
  }
  for (const std::string& w : result->warnings)
    std::cerr << "penumbra render: " << a.scene << ": warning: " << w << "\n";
  penumbra::Stopwatch write_watch;
  const std::optional<float> exposure = png_exposure(
      a, [&] { return sl::auto_exposure(metered ? *metered : result->radiance, options.aov); });
  const penumbra::DisplayOptions display{exposure.value_or(0.0f)};
  if (penumbra::Status s = sl::write_images(a.outputs, result->radiance, options.aov, display);
      !s) {
    std::cerr << "penumbra render: " << s.error().message << "\n";
    return kFailure;
  }
  watch_interrupts(false);
  const double write_ms = write_watch.ms();
  const sl::Camera& cam = scene->camera;
  if (a.json) {
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();  // in pipeline order
    for (const sl::StageTime& s : result->stages) stages[s.name] = s.ms;
    nlohmann::json parameters = {{"bounces", options.bounces},
                                 {"threads", options.threads},
                                 {"aov", sl::to_string(options.aov)},
                                 {"max_memory", options.max_memory}};
    for (const sl::Parameter& p : sl::describe(*result))
      std::visit([&](const auto& v) { parameters[p.name] = v; }, p.value);
    nlohmann::ordered_json j = {
        {"method", sl::to_string(options.method)},
        {"dimensions", 3},
        {"device", result->device},
        {"scene", a.scene},
        {"width", cam.width},
        {"height", cam.height},
        {"time_ms", result->time_ms},
        {"stages", stages},
        {"load_ms", load_ms},
        {"write_ms", write_ms},
        {"memory_bytes", result->memory_bytes},
        {"rays", result->rays},
        {"samples", result->samples},
        {"cancelled", result->cancelled},
        {"warnings", result->warnings},
        {"parameters", parameters},
        {"exposure", exposure ? nlohmann::ordered_json(*exposure) : nlohmann::ordered_json()},
        {"exposure_auto", !a.exposure},
        {"exposure_from", a.exposure_from.empty() ? nlohmann::ordered_json()
                                                  : nlohmann::ordered_json(a.exposure_from)},
        {"outputs", a.outputs}};
    std::cout << j.dump(2) << "\n";
  } else if (!a.quiet) {
    std::size_t triangles = 0;
    for (const sl::TriangleMesh& m : scene->meshes) triangles += m.triangles.size();
    std::printf(
        "penumbra %s: %s (3D), %dx%d pixels, %zu triangles, %zu spheres, %zu disks, "
        "method %s on %s",
        penumbra::kVersion, a.scene.c_str(), cam.width, cam.height, triangles,
        scene->spheres.size(), scene->disks.size(), sl::to_string(options.method),
        result->device.c_str());
    if (options.aov != sl::Aov::radiance)
      std::printf(", %s\n", sl::to_string(options.aov));
    else
      std::printf("%s\n", sl::describe_line(*result).c_str());
    std::printf("  %-24s %9.1f ms\n", "load scene", load_ms);
    for (const sl::StageTime& s : result->stages)
      std::printf("  %-24s %9.1f ms\n", s.name.c_str(), s.ms);
    std::printf("  %-24s %9.1f ms  (computation)\n", "total", result->time_ms);
    std::printf("  %-24s %9.1f ms\n", "write outputs", write_ms);
    std::printf("  working memory %.1f MiB, %.1f M rays traced (%.2f M/s)\n",
                double(result->memory_bytes) / (1 << 20), double(result->rays) / 1e6,
                double(result->rays) / 1e3 / result->time_ms);
    for (const std::string& out : a.outputs) std::printf("  wrote %s\n", out.c_str());
    print_png_exposure(a, exposure);
  }
  // Ctrl-C while the outputs were written: they were finished, and the exit says it came.
  if (result->cancelled || g_cancel.load()) {
    std::fprintf(stderr,
                 "penumbra render: interrupted; wrote the image of %llu samples per pixel\n",
                 (unsigned long long)result->samples);
    return kInterrupted;
  }
  return 0;
}
