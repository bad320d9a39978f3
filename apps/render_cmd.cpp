// `penumbra render`: load or build a scene, render it with one method, write the images, and
// report timings (a table, or JSON).
#include "render_cmd.hpp"

#include <tbb/task_arena.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_enums.hpp"
#include "core/timer.hpp"
#include "io/path_util.hpp"
#include "parse.hpp"
#include "penumbra/penumbra.hpp"
#include "progress.hpp"
#include "render_options.hpp"

namespace {

constexpr int kUsage = 2;
constexpr int kFailure = 1;
constexpr int kInterrupted = 130;  // the shell's code for SIGINT; the output is still written

nlohmann::json parameters_json(const penumbra::flatland::RenderOptions& o) {
  nlohmann::json p = {{"bounces", o.bounces},
                      {"threads", o.threads},
                      {"distance_field", o.distance_field},
                      {"blocks", o.blocks},
                      {"max_memory", o.max_memory}};
  if (o.method == penumbra::flatland::Method::pt) {
    const penumbra::flatland::PtOptions& pt = o.pt;
    p.update({{"spp", pt.spp},
              {"time", pt.seconds},
              {"nee", pt.nee},
              {"sampler", penumbra::flatland::to_string(pt.sampler)},
              {"seed", pt.seed}});
    return p;
  }
  if (o.method == penumbra::flatland::Method::hrc) {
    p.erase("distance_field");
    p.erase("blocks");
    p.update({{"storage", penumbra::flatland::to_string(o.hrc.storage)},
              {"cross_blur", o.hrc.cross_blur},
              {"blur_near_segment", o.hrc.blur_near},
              {"near_segment", o.hrc.near_segment},
              {"corners", penumbra::flatland::to_string(o.hrc.corners)},
              {"wall_fan", o.hrc.wall_fan},
              {"near_fan", o.hrc.near_fan},
              {"fan_share", o.hrc.fan_share},
              {"even_weight", o.hrc.even_weight}});
    return p;
  }
  const penumbra::flatland::RcOptions& rc = o.rc;
  p.update({{"probe_spacing", rc.probe_spacing},
            {"directions", rc.directions},
            {"branching", rc.branching},
            {"interval", rc.interval},
            {"cascades", rc.cascades},
            {"fix", penumbra::flatland::to_string(rc.fix)},
            {"preaverage", rc.preaverage},
            {"extend", rc.extend}});
  if (rc.extend) p["extend_length"] = rc.extend_length;
  return p;
}

}  // namespace

bool has_png(const std::vector<std::string>& outputs) {
  return std::any_of(outputs.begin(), outputs.end(), [](const std::string& out) {
    return penumbra::io::lowercase_extension(out) == ".png";
  });
}

void print_png_exposure(const RenderArgs& a, std::optional<float> exposure) {
  if (!exposure) return;
  if (!a.exposure_from.empty())
    std::printf("  PNG exposure %+.2f EV (metered on %s)\n", *exposure, a.exposure_from.c_str());
  else
    std::printf("  PNG exposure %+.2f EV (%s)\n", *exposure,
                a.exposure ? "--exposure" : "automatic; --exposure sets it");
}

int read_exposure_source(const RenderArgs& a, std::optional<penumbra::ImageRgb>& image) {
  if (a.exposure_from.empty()) return 0;
  penumbra::Expected<penumbra::ImageRgb> read = penumbra::read_rgb_image(a.exposure_from);
  if (!read) {
    std::cerr << "penumbra render: --exposure-from: " << read.error().message << "\n";
    return kUsage;
  }
  image = std::move(*read);
  return 0;
}

int check_render_args(const RenderArgs& a, std::uint64_t& max_memory) {
  for (const std::string& out : a.outputs)
    if (!penumbra::is_supported_output(out)) {
      std::cerr << "penumbra render: " << out << ": unknown output type (use .png, .exr or .pfm)\n";
      return kUsage;
    }
  // Refuse unwritable outputs before spending time on the render.
  for (const std::string& out : a.outputs)
    if (penumbra::Status s = penumbra::check_output(out); !s) {
      std::cerr << "penumbra render: " << s.error().message << "\n";
      return kFailure;
    }
  if (!parse_bytes(a.max_memory, max_memory)) {
    std::cerr << "penumbra render: --max-memory: expected a size such as 512M or 8G, found '"
              << a.max_memory << "'\n";
    return kUsage;
  }
  return 0;
}

namespace {

// A 3D-only option given with a 2D scene, or nullptr.
const CLI::Option* given_3d_option(const RenderArgs& a) {
  if (!a.app) return nullptr;
  for (const CLI::Option* opt : a.app->get_options()) {
    if (opt->count() == 0) continue;
    const std::string name = opt->get_name();
    for (std::string_view n : k3dOptions)
      if (name == n) return opt;
    // A 3D method's option that no 2D method reads.
    if (read_by_3d_method(name) && !listed(name, kPt2dOptions) && !listed(name, kRc2dOptions) &&
        !listed(name, kHrc2dOptions) && !listed(name, kTraversalOptions))
      return opt;
  }
  return nullptr;
}

// An option of another 2D method given: refused, naming the methods that read it (as
// render3d_cmd.cpp refuses in 3D), rather than ignored.
int check_method_options(const RenderArgs& a, penumbra::flatland::Method method) {
  if (!a.app) return 0;
  using penumbra::flatland::Method;
  for (const CLI::Option* opt : a.app->get_options()) {
    if (opt->count() == 0) continue;
    const std::string name = opt->get_name();
    std::string readers;
    bool read = false;
    for (const penumbra::flatland::MethodInfo& m : penumbra::flatland::methods()) {
      const bool reads = (m.method == Method::pt && listed(name, kPt2dOptions)) ||
                         (m.method == Method::rc && listed(name, kRc2dOptions)) ||
                         (m.method == Method::hrc && listed(name, kHrc2dOptions)) ||
                         (m.skips_empty_space && listed(name, kTraversalOptions));
      if (!reads) continue;
      readers += std::string(readers.empty() ? "--method " : " or ") + m.name;
      read = read || m.method == method;
    }
    if (!readers.empty() && !read) {
      std::cerr << "penumbra render: " << name << " applies to " << readers << " only, not "
                << penumbra::flatland::to_string(method)
                << (a.method.empty() ? " (the default)" : "") << "\n";
      return kUsage;
    }
  }
  return 0;
}

int render_scene(const RenderArgs& a) {
  if (!a.scene.empty()) {
    penumbra::Expected<int> dims = penumbra::spaceland::scene_dimensions(a.scene);
    if (!dims) {
      std::cerr << "penumbra render: " << dims.error().message << "\n";
      return kFailure;
    }
    if (*dims == 3) return render_scene_3d(a);
  }
  if (const CLI::Option* opt = given_3d_option(a)) {
    std::cerr << "penumbra render: " << opt->get_name() << " applies to 3D scenes only ("
              << (a.scene.empty() ? std::string("the built-in scene") : a.scene)
              << " is a 2D scene)\n";
    return kUsage;
  }
  penumbra::flatland::RenderOptions options = a.options;
  if (!a.method.empty()) {
    bool known = false;
    for (const penumbra::flatland::MethodInfo& m : penumbra::flatland::methods())
      if (a.method == m.name) {
        options.method = m.method;
        known = true;
      }
    if (!known) {
      std::cerr << "penumbra render: --method " << a.method << " is a 3D method; 2D methods:";
      for (const penumbra::flatland::MethodInfo& m : penumbra::flatland::methods())
        std::cerr << " " << m.name;
      std::cerr << "\n";
      return kUsage;
    }
  }
  if (int code = check_render_args(a, options.max_memory); code != 0) return code;
  if (int code = check_method_options(a, options.method); code != 0) return code;
  std::optional<penumbra::ImageRgb> metered;
  if (int code = read_exposure_source(a, metered); code != 0) return code;
  finish_render_options(options, a.flags);

  penumbra::Stopwatch load_watch;
  penumbra::Expected<penumbra::flatland::SceneDesc> desc =
      a.scene.empty()
          ? penumbra::Expected<penumbra::flatland::SceneDesc>(penumbra::flatland::default_scene())
          : penumbra::flatland::load_scene(a.scene);
  if (!desc) {
    std::cerr << "penumbra render: " << desc.error().message << "\n";
    return kFailure;
  }
  // Option values that cannot work for this grid are usage errors.
  if (penumbra::Status s = penumbra::flatland::check_options(desc->width, desc->height, options);
      !s) {
    std::cerr << "penumbra render: " << with_flags(s.error().message) << "\n";
    return kUsage;
  }
  // A scene whose fluence a float cannot hold names its brightest value.
  if (penumbra::Status s = penumbra::flatland::check_brightness(*desc, options); !s) {
    std::cerr << "penumbra render: " << s.error().message << "\n";
    return kFailure;
  }
  // Refuse up front, before the grid itself is allocated.
  if (penumbra::Status s =
          penumbra::flatland::check_memory(desc->width, desc->height, options, true);
      !s) {
    std::cerr << "penumbra render: " << desc->source << ": " << with_flags(s.error().message)
              << "\n";
    return kFailure;
  }
  // Rasterising runs on the same number of threads as the method.
  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  penumbra::Stopwatch raster_watch;
  penumbra::Expected<penumbra::flatland::Scene> scene =
      arena.execute([&] { return penumbra::flatland::build_scene(*desc); });
  if (!scene) {
    std::cerr << "penumbra render: " << scene.error().message << "\n";
    return kFailure;
  }
  const double raster_ms = raster_watch.ms();
  const double load_ms = load_watch.ms() - raster_ms;

  // Progressive methods report progress on a terminal and stop early on Ctrl-C.
  const bool progress = !a.quiet && isatty(STDERR_FILENO);
  if (options.method == penumbra::flatland::Method::pt) {
    if (progress) options.progress = draw_progress;
    options.cancel = &g_cancel;
    watch_interrupts(true);
  }
  penumbra::Expected<penumbra::flatland::RenderResult> result =
      penumbra::flatland::render(*scene, options);
  // The path tracer keeps watching Ctrl-C until its outputs are written, so that they are
  // finished rather than lost (docs/RELIABILITY.md).
  if (progress && options.method == penumbra::flatland::Method::pt) std::fprintf(stderr, "\n");
  if (!result) {
    std::cerr << "penumbra render: " << desc->source << ": " << with_flags(result.error().message)
              << "\n";
    return kFailure;
  }
  penumbra::Stopwatch write_watch;
  const std::optional<float> exposure = png_exposure(a, [&] {
    return penumbra::flatland::auto_exposure(metered ? *metered : result->fluence, &*scene);
  });
  const penumbra::DisplayOptions display{exposure.value_or(0.0f), a.show_walls};
  // All outputs or none; files already there stay untouched if any output fails.
  if (penumbra::Status s =
          penumbra::flatland::write_images(a.outputs, result->fluence, *scene, display);
      !s) {
    std::cerr << "penumbra render: " << s.error().message << "\n";
    return kFailure;
  }
  watch_interrupts(false);
  const double write_ms = write_watch.ms();

  if (a.json) {
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();  // in pipeline order
    // What the stages that count their work computed (StageTime::work).
    nlohmann::ordered_json work = nlohmann::ordered_json::object();
    for (const penumbra::flatland::StageTime& s : result->stages) {
      stages[s.name] = s.ms;
      if (s.work > 0) work[s.name] = s.work;
    }
    nlohmann::ordered_json j = {
        {"method", penumbra::flatland::to_string(options.method)},
        {"device", result->device},
        {"scene", desc->source},
        {"width", scene->width},
        {"height", scene->height},
        {"time_ms", result->time_ms},
        {"stages", stages},
        {"stage_work", work},
        {"rasterize_ms", raster_ms},
        {"load_ms", load_ms},
        {"write_ms", write_ms},
        {"memory_bytes", result->memory_bytes},
        {"gpu_memory_bytes", result->gpu_memory_bytes},
        {"uploaded_bytes", result->uploaded_bytes},
        {"intervals", result->intervals},
        {"samples", result->samples},
        {"cancelled", result->cancelled},
        {"parameters", parameters_json(result->options)},
        {"exposure", exposure ? nlohmann::ordered_json(*exposure) : nlohmann::ordered_json()},
        {"exposure_auto", !a.exposure},
        {"exposure_from", a.exposure_from.empty() ? nlohmann::ordered_json()
                                                  : nlohmann::ordered_json(a.exposure_from)},
        {"show_walls", a.show_walls},
        {"outputs", a.outputs}};
    std::cout << j.dump(2) << "\n";
  } else if (!a.quiet) {
    std::printf("penumbra %s: %s, %dx%d cells, method %s on %s, ", penumbra::kVersion,
                desc->source.c_str(), scene->width, scene->height,
                penumbra::flatland::to_string(options.method), result->device.c_str());
    if (options.method == penumbra::flatland::Method::pt)
      std::printf("%llu samples per cell, sampler %s%s\n", (unsigned long long)result->samples,
                  penumbra::flatland::to_string(options.pt.sampler), options.pt.nee ? ", nee" : "");
    else if (options.method == penumbra::flatland::Method::hrc)
      std::printf("storage %s, cross blur %s\n", penumbra::flatland::to_string(options.hrc.storage),
                  !options.hrc.cross_blur ? "off"
                  : options.hrc.blur_near ? "on the whole fluence"
                                          : "on the light from beyond the near segment");
    else
      std::printf("%d cascades, fix %s\n", result->options.rc.cascades,
                  penumbra::flatland::to_string(options.rc.fix));
    std::printf("  %-24s %9.1f ms\n", "load scene", load_ms);
    std::printf("  %-24s %9.1f ms\n", "rasterise", raster_ms);
    for (const penumbra::flatland::StageTime& s : result->stages)
      std::printf("  %-24s %9.1f ms\n", s.name.c_str(), s.ms);
    std::printf("  %-24s %9.1f ms  (computation)\n", "total", result->time_ms);
    std::printf("  %-24s %9.1f ms\n", "write outputs", write_ms);
    std::printf(options.method == penumbra::flatland::Method::pt
                    ? "  working memory %.1f MiB, %.1f M rays traced (%.1f M/s)\n"
                    : "  working memory %.1f MiB, %.1f M intervals traced (%.1f M/s)\n",
                double(result->memory_bytes) / (1 << 20), double(result->intervals) / 1e6,
                double(result->intervals) / 1e3 / result->time_ms);
    if (result->gpu_memory_bytes > 0)
      std::printf("  GPU memory %.1f MiB, %.2f MiB uploaded\n",
                  double(result->gpu_memory_bytes) / (1 << 20),
                  double(result->uploaded_bytes) / (1 << 20));
    for (const std::string& out : a.outputs) std::printf("  wrote %s\n", out.c_str());
    print_png_exposure(a, exposure);
  }
  // Ctrl-C while the outputs were written: they were finished, and the exit says it came.
  if (result->cancelled || g_cancel.load()) {
    std::fprintf(stderr, "penumbra render: interrupted; wrote the image of %llu samples per cell\n",
                 (unsigned long long)result->samples);
    return kInterrupted;
  }
  return 0;
}

}  // namespace

bool RenderCommand::parsed() const {
  return app->parsed();
}

std::unique_ptr<RenderCommand> add_render_command(CLI::App& app) {
  auto cmd = std::make_unique<RenderCommand>();
  RenderArgs& a = cmd->args;
  CLI::App* render =
      app.add_subcommand("render", "Render a 2D or 3D scene file (or the built-in 2D scene)");
  cmd->app = render;
  a.app = render;
  render
      ->add_option("scene", a.scene,
                   "Scene file (JSON, format 1; 2D or 3D by its `dimensions`); omitted: the "
                   "built-in 2D scene")
      ->check(non_empty_path());
  render
      ->add_option("-o,--output", a.outputs,
                   "Output file: .png (display), .exr or .pfm (2D fluence, 3D radiance); "
                   "repeatable")
      ->required();
  // --method names a method of either world: the scene decides which table it is looked up in.
  {
    std::vector<std::string> names;
    std::string help = "Method (default: rc for a 2D scene, pt for a 3D one). 2D:";
    for (const penumbra::flatland::MethodInfo& m : penumbra::flatland::methods()) {
      names.push_back(m.name);
      help += std::string(names.size() > 1 ? ";" : "") + " " + m.name + ", " + m.summary +
              (m.gpu ? "" : " (CPU only)");
    }
    help += ". 3D:";
    bool first = true;
    for (const penumbra::spaceland::MethodInfo& m : penumbra::spaceland::methods()) {
      if (std::find(names.begin(), names.end(), m.name) == names.end()) names.push_back(m.name);
      help += std::string(first ? "" : ";") + " " + m.name + ", " + m.summary;
      first = false;
    }
    render->add_option("--method", a.method, help)->check(CLI::IsMember(names));
  }
  render->add_option("--width", a.width, "3D: image width (the camera's fov_y is kept)")
      ->check(CLI::Range(1, penumbra::spaceland::kMaxImageSide));
  render->add_option("--height", a.height, "3D: image height")
      ->check(CLI::Range(1, penumbra::spaceland::kMaxImageSide));
  {
    namespace sl = penumbra::spaceland;
    add_enum_option(render, "--aov", a.aov,
                    {sl::Aov::radiance, sl::Aov::depth, sl::Aov::normal, sl::Aov::albedo,
                     sl::Aov::position, sl::Aov::emission, sl::Aov::object},
                    "3D: what the image holds: radiance, or a G-buffer channel of the first "
                    "hits (depth, normal, albedo, position, emission, object)");
    add_enum_option(render, "--merge", a.spwi.merge,
                    {sl::SpwiMerge::bilinear, sl::SpwiMerge::bilateral, sl::SpwiMerge::bilinear3d,
                     sl::SpwiMerge::fix, sl::SpwiMerge::minmax},
                    "3D spwi (ssrc: the first four; default bilateral): merging with the upper "
                    "cascade: bilinear, bilateral (depth edges), bilinear3d (world-space lines), "
                    "fix (trace to each upper probe's interval start), minmax (probes on each "
                    "tile's nearest and farthest surface)");
    add_enum_option(render, "--sun", a.spwi.sun, {sl::SpwiSun::direct, sl::SpwiSun::cascades},
                    "3D spwi: the sun on visible surfaces: direct (a shadow ray per pixel), "
                    "cascades (the top cascade sees its disk)");
    render
        ->add_option("--voxel", a.grid.voxel,
                     "3D grid (and spwi's radiance cache, for later bounces): voxel size in world "
                     "units, of the finest level (0: the scene's "
                     "longest side over 128, or the median distance to what the camera sees "
                     "over 32 where finer; larger if that passes a quarter of --max-memory)")
        ->check(real_above(0, true))
        ->capture_default_str();
    render
        ->add_option("--levels", a.grid.levels,
                     "3D grid (and spwi's radiance cache): nested grids around the camera, voxels "
                     "doubling per level, each "
                     "136 voxels wide, the last holding the scene (0: as many as that takes; 1: "
                     "one grid over the whole scene)")
        ->capture_default_str();
    render
        ->add_option("--cache-probe-spacing", a.cache_probe_spacing,
                     "3D spwi's radiance cache (later bounces): voxels between its cascade-0 "
                     "probes")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
    render
        ->add_option(
            "--sun-rays", a.sun_rays,
            "3D spwi, grid and ssrc: shadow rays over the sun's disk at each visible surface, "
            "for soft shadows (1: one towards its centre, hard shadows)")
        ->check(CLI::Range(1, 1024))
        ->capture_default_str();
    render
        ->add_option("--sectors", a.ssrc.sectors,
                     "3D ssrc: occlusion sectors per screen direction, equal angles from the view "
                     "vector to its opposite: 8, 16 or 32 (a 32, 64 or 128-bit mask for four "
                     "directions)")
        ->check(CLI::IsMember({8, 16, 32}))
        ->capture_default_str();
    render
        ->add_option("--steps", a.ssrc.steps,
                     "3D ssrc: samples an interval at least (each cascade reads the finest "
                     "depth-pyramid level that leaves this many)")
        ->check(CLI::Range(1, 256))
        ->capture_default_str();
    render->add_flag("--backfaces", a.ssrc.backfaces,
                     "3D ssrc: a depth sample is solid to where its camera ray leaves its object "
                     "(one more ray a pixel), --thickness only where nothing of it lies behind");
    render
        ->add_option("--march-rays", a.ssrc.rays,
                     "3D ssrc: screen directions marched together: 1, 2 or 4 (the same image)")
        ->check(CLI::IsMember({1, 2, 4}))
        ->capture_default_str();
    render
        ->add_option("--thickness", a.ssrc.thickness,
                     "3D ssrc: each depth sample is solid to this fraction of its depth behind it "
                     "(1e30: infinitely thick, as horizon-based methods assume)")
        ->check(real_range(0, 1e30))
        ->capture_default_str();
    render
        ->add_option("--texel-size", a.surface.texel_size,
                     "3D surface: the atlas's texel side in world units (0: from --texels)")
        ->check(real_range(0, 1e30))
        ->capture_default_str();
    render
        ->add_option("--texels", a.surface.texels,
                     "3D surface: about how many texels the atlas gives the surfaces, where "
                     "--texel-size is 0")
        ->check(CLI::Range(std::uint64_t(64), std::uint64_t(1) << 28))
        ->capture_default_str();
    render
        ->add_option("--refine", a.surface.refine,
                     "3D surface: texels up to 2^N times finer towards the lights, under 1/16 of "
                     "the distance to the nearest (0: one texel size)")
        ->check(CLI::Range(0, 10))
        ->capture_default_str();
    render->add_option("--atlas", a.surface.atlas,
                       "3D surface: view from this atlas (made by `penumbra bake` for the same "
                       "scene and --bounces) instead of baking: no cascade is traced");
    add_enum_option(render, "--offscreen", a.ssrc.offscreen,
                    {sl::SsrcOffscreen::sky, sl::SsrcOffscreen::world},
                    "3D ssrc: what a ray sees once its march leaves the screen: the sky, or the "
                    "world (an exact ray on through the scene, as SPWI's: light from off screen, "
                    "rooms; a cost that depends on the scene)");
    add_enum_option(
        render, "--gather", a.spwi.gather, {sl::SpwiGather::pixel, sl::SpwiGather::probe},
        "3D spwi and ssrc: the final gather averages each probe's directions per pixel, over "
        "the pixel's hemisphere (pixel), or once per probe, over its own (probe)");
    add_enum_option(render, "--specular", a.spwi.specular,
                    {sl::SpecularQuery::cone, sl::SpecularQuery::wide, sl::SpecularQuery::ray},
                    "3D, glossy materials: the specular lobe from the cone query (spwi and "
                    "grid: cascades 0..K-1 unmerged, K merged, K from the roughness), the widest "
                    "query (merged cascade 0 alone; ssrc's and surface's only query), or (spwi) "
                    "one exact ray along the mirror direction (a baseline)");
    render
        ->add_option("--depth-bias", a.spwi.depth_bias,
                     "3D spwi: probes moved to this fraction of their depth (seed 000: 0.98)")
        ->check(real_range(1e-3, 1))
        ->capture_default_str();
    render->add_flag("--disjoint", a.disjoint,
                     "3D spwi: cascades above 0 trace only their interval (the thesis), not from "
                     "their probe (which stops light through walls near probes)");
    render
        ->add_option("--merge-edge", a.spwi.merge_edge,
                     "3D spwi and ssrc, bilateral merge: depth range over mean that is an edge")
        ->check(real_range(0, 1e6))
        ->capture_default_str();
    render
        ->add_option(
            "--gather-normal", a.spwi.gather_normal,
            "3D spwi and ssrc: final gather weights times cos^p of the probe's and the pixel's "
            "normals (0: off, as seed 000)")
        ->check(real_range(0, 64))
        ->capture_default_str();
    render
        ->add_option("--gather-edge", a.spwi.gather_edge,
                     "3D spwi and ssrc: the same test in the final gather")
        ->check(real_range(0, 1e6))
        ->capture_default_str();
  }
  RenderOptionSet all;
  all.pt = all.rc = all.device = all.storage = all.hrc = true;
  all.bounces = all.threads = all.traversal = true;
  add_render_options(render, a.options, a.flags, all);
  render->add_option("--max-memory", a.max_memory, "Refuse work needing more working memory")
      ->capture_default_str();
  CLI::Option* exposure =
      add_exposure_option(render, a.exposure,
                          "PNG exposure in EV (default: automatic, the median of the lit open "
                          "cells or pixels to 1/8; --json reports it)");
  render
      ->add_option("--exposure-from", a.exposure_from,
                   "PNG exposure metered as the automatic one, on this image (.pfm or .exr of "
                   "the same scene, e.g. a reference) instead of the render: renders of one "
                   "scene by several methods exposed alike")
      ->excludes(exposure);
  // Two flags rather than CLI11's "--show-walls,!--no-show-walls", whose help line reads
  // "{false}" beside a default that is on.
  CLI::Option* show = render->add_flag(
      "--show-walls", a.show_walls,
      "2D PNG (the default): walls and fog in the dark keep a dim floor of their colour, as the "
      "painter shows them");
  render
      ->add_flag_callback(
          "--no-show-walls", [&a] { a.show_walls = false; },
          "2D PNG: unlit walls and fog black, the fluence as it is")
      ->excludes(show);
  render->add_flag("--json", a.json, "Print one JSON object with timings, memory and parameters");
  render->add_flag("-q,--quiet", a.quiet, "Print nothing on success");
  return cmd;
}

int run_render(const RenderArgs& a) {
  try {
    return render_scene(a);
  } catch (const std::exception& e) {  // the library reports errors as values; this is a bug
    std::cerr << "penumbra render: internal error: " << e.what() << "\n";
    return kFailure;
  }
}
