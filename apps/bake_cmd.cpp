#include "bake_cmd.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli_enums.hpp"
#include "core/timer.hpp"
#include "io/path_util.hpp"
#include "parse.hpp"
#include "penumbra/penumbra.hpp"
#include "render_options.hpp"

namespace {

constexpr int kUsage = 2;
constexpr int kFailure = 1;

namespace sl = penumbra::spaceland;

int fail(int code, const std::string& message) {
  std::cerr << "penumbra bake: " << message << "\n";
  return code;
}

}  // namespace

bool BakeCommand::parsed() const {
  return app && app->parsed();
}

std::unique_ptr<BakeCommand> add_bake_command(CLI::App& app) {
  auto cmd = std::make_unique<BakeCommand>();
  BakeArgs& a = cmd->args;
  CLI::App* bake = app.add_subcommand(
      "bake",
      "Bake a 3D scene's light into its surface atlas (surface radiance cascades) for "
      "`render --method surface --atlas`");
  cmd->app = bake;
  bake->add_option("scene", a.scene, "3D scene file (.json)")->required();
  bake->add_option("-o,--output", a.output, "The atlas (.exr)")->required();
  bake->add_option("--texel-size", a.surface.texel_size,
                   "The atlas's texel side in world units (0: from --texels)")
      ->check(real_range(0, 1e30))
      ->capture_default_str();
  bake->add_option("--texels", a.surface.texels,
                   "About how many texels the atlas gives the surfaces, where --texel-size is 0")
      ->check(CLI::Range(std::uint64_t(64), std::uint64_t(1) << 28))
      ->capture_default_str();
  bake->add_option("--refine", a.surface.refine,
                   "Texels up to 2^N times finer towards the lights, under 1/16 of the distance "
                   "to the nearest (0: one texel size)")
      ->check(CLI::Range(0, 10))
      ->capture_default_str();
  bake->add_option("--directions", a.surface.directions,
                   "Q0: cascade 0's directions over the sphere (4, 16, 64, ... 4096)")
      ->capture_default_str();
  bake->add_option("--interval", a.surface.interval,
                   "t0: cascade 0's interval in world units (0: two texels)")
      ->check(real_range(0, 1e30))
      ->capture_default_str();
  bake->add_option("--cascades", a.surface.cascades,
                   "Cascades (0: until an interval spans the scene)")
      ->check(CLI::Range(0, 12))
      ->capture_default_str();
  bake->add_option("--bounces", a.bounces, "Diffuse bounces (1: direct light only)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  bake->add_option("--threads", a.threads, "Worker threads (0: all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  bake->add_option("--max-memory", a.max_memory, "Refuse work needing more working memory")
      ->capture_default_str();
  bake->add_flag("--no-radiance", a.no_radiance,
                 "Write the irradiance only, not cascade 0's radiance per direction (what glossy "
                 "queries read; Q0 x 3 channels)");
  bake->add_flag("--json", a.json, "Print one JSON object with timings, memory and the atlas");
  bake->add_flag("-q,--quiet", a.quiet, "Print nothing on success");
  return cmd;
}

int run_bake(const BakeArgs& a) {
  if (penumbra::io::lowercase_extension(a.output) != ".exr")
    return fail(kUsage, a.output + ": an atlas is written as .exr");
  if (penumbra::Status s = penumbra::check_output(a.output); !s)
    return fail(kFailure, s.error().message);
  sl::RenderOptions options;
  options.method = sl::Method::surface;
  options.surface = a.surface;
  options.bounces = a.bounces;
  options.threads = a.threads;
  if (!parse_bytes(a.max_memory, options.max_memory))
    return fail(kUsage,
                "--max-memory: expected a size such as 512M or 8G, found '" + a.max_memory + "'");
  if (penumbra::Status s = sl::check_options(options); !s)
    return fail(kUsage, with_flags(s.error().message));

  penumbra::Stopwatch load_watch;
  penumbra::Expected<sl::Scene> scene = sl::load_scene(a.scene, {options.max_memory});
  if (!scene) return fail(kFailure, with_flags(scene.error().message));
  const double load_ms = load_watch.ms();
  penumbra::Expected<sl::BakeResult> r = sl::bake(*scene, options, a.output, !a.no_radiance);
  if (!r) return fail(kFailure, a.scene + ": " + with_flags(r.error().message));

  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(r->scene_hash));
  if (a.json) {
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();
    for (const sl::StageTime& s : r->stages) stages[s.name] = s.ms;
    nlohmann::ordered_json cascades = nlohmann::ordered_json::array();
    for (std::size_t i = 0; i < r->probes.size(); ++i)
      cascades.push_back({{"probes", r->probes[i]}, {"store_bytes", r->store_bytes[i]}});
    nlohmann::ordered_json j = {{"scene", a.scene},
                                {"output", a.output},
                                {"scene_hash", hash},
                                {"atlas",
                                 {{"width", r->width},
                                  {"height", r->height},
                                  {"charts", r->charts},
                                  {"lightmap_charts", r->lightmap_charts},
                                  {"covered_texels", r->covered},
                                  {"radiance", r->radiance}}},
                                {"parameters",
                                 {{"texel_size", r->used.texel_size},
                                  {"texels", r->used.texels},
                                  {"refine", r->used.refine},
                                  {"directions", r->used.directions},
                                  {"interval", r->used.interval},
                                  {"cascades", r->used.cascades},
                                  {"bounces", options.bounces},
                                  {"threads", options.threads},
                                  {"max_memory", options.max_memory}}},
                                {"cascades", cascades},
                                {"load_ms", load_ms},
                                {"stages", stages},
                                {"time_ms", r->time_ms},
                                {"memory_bytes", r->memory_bytes},
                                {"rays", r->rays},
                                {"file_bytes", r->file_bytes}};
    std::cout << j.dump(2) << "\n";
  } else if (!a.quiet) {
    std::printf(
        "penumbra %s: %s (3D) baked: %dx%d atlas, %zu charts (%zu from lightmap UVs), %llu "
        "texels on surfaces; texel %g (down to 1/%d towards the lights), Q0 %d, t0 %g, %d "
        "cascades, %d bounce(s)\n",
        penumbra::kVersion, a.scene.c_str(), r->width, r->height, r->charts, r->lightmap_charts,
        static_cast<unsigned long long>(r->covered), double(r->used.texel_size),
        1 << r->used.refine, r->used.directions, double(r->used.interval), r->used.cascades,
        options.bounces);
    std::printf("  %-24s %9.1f ms\n", "load scene", load_ms);
    for (const sl::StageTime& s : r->stages)
      std::printf("  %-24s %9.1f ms\n", s.name.c_str(), s.ms);
    std::printf("  %-24s %9.1f ms\n", "total", r->time_ms);
    std::printf("  working memory %.1f MiB, %.1f M rays traced\n",
                double(r->memory_bytes) / (1 << 20), double(r->rays) / 1e6);
    std::printf("  wrote %s (%.1f MiB%s), scene hash %s\n", a.output.c_str(),
                double(r->file_bytes) / (1 << 20),
                r->radiance ? ", with the radiance per direction" : "", hash);
  }
  return 0;
}
