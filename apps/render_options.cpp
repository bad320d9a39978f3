#include "render_options.hpp"

#include <CLI/CLI.hpp>
#include <utility>

#include "cli_enums.hpp"
#include "io/json_reader.hpp"
#include "penumbra/spaceland/render.hpp"

using namespace penumbra::flatland;

void add_render_options(CLI::App* app, RenderOptions& options, RenderOptionFlags& flags,
                        const RenderOptionSet& which) {
  if (which.method) {
    std::vector<penumbra::flatland::Method> list = which.methods;
    std::string help = which.method_help;
    if (list.empty()) {  // the method table: names and help from the library
      help += ":";
      for (const penumbra::flatland::MethodInfo& m : penumbra::flatland::methods()) {
        list.push_back(m.method);
        help += std::string(list.size() > 1 ? ";" : "") + " " + m.name + ", " + m.summary +
                (m.gpu ? "" : " (CPU only)");
      }
    }
    add_enum_option(app, "--method", options.method, list, help);
  }
  if (which.pt) {
    PtOptions& pt = options.pt;
    flags.spp =
        app->add_option(
               "--spp", pt.spp,
               "pt: samples per cell, or per pixel in 3D (with --time: the most; 0: no limit)")
            ->check(CLI::Range(0, 1 << 30))
            ->capture_default_str();
    flags.time =
        app->add_option("--time", pt.seconds, "pt: add samples until this many seconds have passed")
            ->check(real_above(0, true));
    app->add_flag(
        "--nee", pt.nee,
        "2D pt: next event estimation (aim at emitting regions, combined by MIS; the 3D path "
        "tracer always does)");
    add_enum_option(
        app, "--sampler", pt.sampler, {Sampler::r1, Sampler::random},
        "2D pt: direction sequence: r1 (low discrepancy) or random (the 3D path tracer always "
        "takes Owen-scrambled Sobol points)");
    app->add_option("--seed", pt.seed, "pt: random seed")
        ->check(uint64_text())
        ->capture_default_str();
  }
  if (which.rc) {
    RcOptions& rc = options.rc;
    // 2D and 3D share these flags with different units and defaults, so the help states each
    // world's default (from the option structs) rather than 2D's alone.
    const penumbra::spaceland::SpwiOptions spwi;
    const penumbra::spaceland::GridOptions grid;
    auto n = [](auto v) { return penumbra::io::format_number(double(v)); };
    app->add_option("--probe-spacing", rc.probe_spacing,
                    "Cascade-0 probe spacing s0: cells in 2D (default " + n(rc.probe_spacing) +
                        "), pixels in 3D spwi and ssrc (default " +
                        n(penumbra::spaceland::kSpwiSpacing) +
                        ", or its half where that leaves under " +
                        n(penumbra::spaceland::kSpwiProbesAcross) +
                        " probes across the image's shorter side), voxels in the 3D grid "
                        "(default " +
                        n(grid.probe_spacing) + ")")
        ->check(CLI::Range(1, 64));
    app->add_option("--directions", rc.directions,
                    "Directions Q0 of a cascade-0 probe: 1 to 64 in 2D (default " +
                        n(rc.directions) +
                        "); in 3D spwi and the grid the square of a power of two (spwi default " +
                        n(spwi.directions) + ", grid " + n(grid.directions) +
                        "), ssrc a power of two up to 256, screen directions (default " +
                        n(penumbra::spaceland::SsrcOptions{}.directions) +
                        "), surface the square of a power of two over the sphere (default " +
                        n(penumbra::spaceland::SurfaceOptions{}.directions) + ")")
        ->check(CLI::Range(1, 1024));
    app->add_option("--branching", rc.branching,
                    "Angular branching per cascade: 2 or 4 (2D); 4 or 16 (3D spwi, default 4)")
        ->check(CLI::IsMember({2, 4, 16}))
        ->capture_default_str();
    app->add_option(
           "--interval", rc.interval,
           "Cascade-0 interval length t0: cells in 2D (default " + n(rc.interval) +
               "); world units in 3D (default: spwi, four probe spacings at the median depth; "
               "grid, four probe spacings; surface, two texels); whole pixels in 3D ssrc "
               "(default four probe spacings)")
        ->check(real_above(0, false));
    app->add_option("--cascades", rc.cascades,
                    "Number of cascades (default 0: enough to reach across the 2D grid or the 3D "
                    "scene)")
        ->check(CLI::Range(0, 16))
        ->capture_default_str();
    // No default shown: it differs between worlds (the help would say bilinear for the grid).
    add_enum_option(app, "--fix", rc.fix, {MergeFix::bilinear, MergeFix::none, MergeFix::nearest},
                    "Merge: bilinear (fix), none (vanilla), nearest (2D default: bilinear); 3D "
                    "grid: bilinear or none (default: none)")
        ->default_str("");
    app->add_flag("--preaverage", rc.preaverage,
                  "Trace a 2x2 sub-probe neighbourhood and store the average");
    app->add_flag("--extend", rc.extend,
                  "Build long intervals by extending a short traced one (2D; 3D grid)");
    app->add_option("--extend-length", rc.extend_length,
                    "Traced length before extension: cells (2D), voxels (3D grid)")
        ->check(real_range(1, 1e6))
        ->capture_default_str();
  }
  if (which.device)
    add_enum_option(app, "--device", options.device, {Device::cpu, Device::gpu, Device::auto_},
                    which.device_help);
  if (which.storage)
    add_enum_option(app, "--storage", options.hrc.storage, {Storage::f32, Storage::f16},
                    "hrc: precision of T and R: f32, f16");
  if (which.hrc) {
    app->add_flag("--no-cross-blur", flags.no_cross_blur, "hrc: skip the 1-cell cross blur");
    app->add_flag("--blur-near-segment", options.hrc.blur_near,
                  "hrc: blur the whole fluence as eq. 21 is written (default: only the light from "
                  "beyond the near segment, so the rims of lights stay sharp)");
    add_enum_option(app, "--corners", options.hrc.corners, {Corners::half, Corners::walls},
                    "hrc: a 45-degree traced ray through a cell corner: half (each opaque cell "
                    "touching it stops half of the ray), walls (only two opaque cells stop it)");
    app->add_flag("--no-near-segment", flags.no_near_segment,
                  "hrc: read R_0([x+1, y]) alone, as the paper (a cell's own medium left out)");
    app->add_option("--wall-fan", options.hrc.wall_fan,
                    "hrc: the fan's cells gather through 2 rays per cone of this cascade (0: no "
                    "fan, every cell reads its quadrants)")
        ->check(CLI::Range(0, penumbra::flatland::kMaxWallFan))
        ->capture_default_str();
    app->add_option("--fan-share", options.hrc.fan_share,
                    "hrc: the share of the cells the fan gathers, the same on every scene: lit "
                    "wall cells and lights' rims first, then the nearest to a rim (0 < share <= 1)")
        ->check(CLI::Validator(
            [](std::string& text) {
              float v = 0;
              const bool ok = CLI::detail::lexical_cast(text, v) && v > 0.0f && v <= 1.0f;
              return ok ? std::string() : "a share of the cells in (0, 1], found " + text;
            },
            "SHARE in (0, 1]"))
        ->capture_default_str();
    app->add_option("--near-fan", options.hrc.near_fan,
                    "hrc: the farthest from a light's rim (cells along x and y) the fan ranks "
                    "cells by their distance; farther ones rank alike, after them")
        ->check(CLI::Range(0, penumbra::flatland::kMaxNearFan))
        ->capture_default_str();
    app->add_option("--even-weight", options.hrc.even_weight,
                    "hrc: eqs. 15-17 at an even probe column, the weight of the cones at its own "
                    "probe against the merges along the edges (the paper: 0.5); in [0, 1]")
        ->check(CLI::Range(0.0f, 1.0f))
        ->capture_default_str();
  }
  if (which.bounces)
    app->add_option("--bounces", options.bounces, which.bounces_help)
        ->check(CLI::Range(1, which.max_bounces))
        ->capture_default_str();
  if (which.threads)
    app->add_option("--threads", options.threads, which.threads_help)
        ->check(CLI::Range(0, 1024))
        ->capture_default_str();
  if (which.traversal) {
    app->add_flag("--no-distance-field", flags.no_distance_field,
                  "Step every cell (plain DDA) instead of jumping over empty space");
    app->add_flag("--no-blocks", flags.no_blocks, "Do not skip empty 8x8 blocks (two-level DDA)");
  }
}

void finish_render_options(RenderOptions& options, const RenderOptionFlags& flags) {
  // Only what was asked for changes: a command that never registered a flag keeps the default.
  if (flags.no_distance_field) options.distance_field = false;
  if (flags.no_blocks) options.blocks = false;
  if (flags.no_cross_blur) options.hrc.cross_blur = false;
  if (flags.no_near_segment) options.hrc.near_segment = false;
  // --time alone runs until the time is up; with --spp too, whichever comes first.
  if (flags.time && flags.spp && flags.time->count() > 0 && flags.spp->count() == 0)
    options.pt.spp = 0;
}

namespace {

// Each RenderOptions field and the flag that sets it; a field set by two flags is listed twice
// (messages name it by the first). Beside add_render_options, so that a flag and its field are
// renamed together.
const std::pair<const char*, const char*> kFlags[] = {
    {"`method`", "--method"},
    {"`device`", "--device"},
    {"`bounces`", "--bounces"},
    {"`threads`", "--threads"},
    {"`max_memory`", "--max-memory"},
    {"`distance_field`", "--no-distance-field"},
    {"`blocks`", "--no-blocks"},
    {"`rc.probe_spacing`", "--probe-spacing"},
    {"`rc.directions`", "--directions"},
    {"`rc.branching`", "--branching"},
    {"`rc.interval`", "--interval"},
    {"`rc.cascades`", "--cascades"},
    {"`rc.fix`", "--fix"},
    {"`rc.preaverage`", "--preaverage"},
    {"`rc.extend_length`", "--extend-length"},
    {"`rc.extend`", "--extend"},
    {"`hrc.storage`", "--storage"},
    {"`hrc.cross_blur`", "--no-cross-blur"},
    {"`hrc.blur_near`", "--blur-near-segment"},
    {"`hrc.near_segment`", "--no-near-segment"},
    {"`hrc.corners`", "--corners"},
    {"`hrc.wall_fan`", "--wall-fan"},
    {"`hrc.near_fan`", "--near-fan"},
    {"`hrc.fan_share`", "--fan-share"},
    {"`hrc.even_weight`", "--even-weight"},
    {"`pt.spp`", "--spp"},
    {"`pt.seconds`", "--time"},
    {"`pt.nee`", "--nee"},
    {"`pt.sampler`", "--sampler"},
    {"`pt.seed`", "--seed"},
    // 3D: SPWI's and the probe grid's own options, and those they share with 2D's cascades.
    {"`spwi.probe_spacing`", "--probe-spacing"},
    {"`spwi.directions`", "--directions"},
    {"`spwi.interval`", "--interval"},
    {"`spwi.branching`", "--branching"},
    {"`spwi.cascades`", "--cascades"},
    {"`spwi.preaverage`", "--preaverage"},
    {"`spwi.depth_bias`", "--depth-bias"},
    {"`spwi.merge_edge`", "--merge-edge"},
    {"`spwi.gather_edge`", "--gather-edge"},
    {"`spwi.gather_normal`", "--gather-normal"},
    {"`ssrc.probe_spacing`", "--probe-spacing"},
    {"`ssrc.directions`", "--directions"},
    {"`ssrc.interval`", "--interval"},
    {"`ssrc.cascades`", "--cascades"},
    {"`ssrc.steps`", "--steps"},
    {"`ssrc.sectors`", "--sectors"},
    {"`ssrc.rays`", "--march-rays"},
    {"`ssrc.thickness`", "--thickness"},
    {"`ssrc.merge_edge`", "--merge-edge"},
    {"`ssrc.gather_edge`", "--gather-edge"},
    {"`ssrc.gather_normal`", "--gather-normal"},
    {"`surface.texel_size`", "--texel-size"},
    {"`surface.texels`", "--texels"},
    {"`surface.refine`", "--refine"},
    {"`surface.atlas`", "--atlas"},
    {"`surface.directions`", "--directions"},
    {"`surface.interval`", "--interval"},
    {"`surface.cascades`", "--cascades"},
    {"`grid.voxel`", "--voxel"},
    {"`grid.levels`", "--levels"},
    {"`cache_probe_spacing`", "--cache-probe-spacing"},
    {"`sun_rays`", "--sun-rays"},
    {"`grid.probe_spacing`", "--probe-spacing"},
    {"`grid.directions`", "--directions"},
    {"`grid.interval`", "--interval"},
    {"`grid.cascades`", "--cascades"},
    {"`grid.extend_length`", "--extend-length"},
    // Fields no message names, listed for the 3D methods' option groups (flags_of).
    {"`spwi.merge`", "--merge"},
    {"`ssrc.merge`", "--merge"},
    {"`ssrc.backfaces`", "--backfaces"},
    {"`spwi.sun`", "--sun"},
    {"`spwi.gather`", "--gather"},
    {"`spwi.specular`", "--specular"},
    {"`grid.specular`", "--specular"},
    {"`ssrc.specular`", "--specular"},
    {"`surface.specular`", "--specular"},
    {"`ssrc.gather`", "--gather"},
    {"`ssrc.offscreen`", "--offscreen"},
    {"`spwi.overlap`", "--disjoint"},
    {"`grid.extend_length`", "--extend"},
    {"`grid.fix`", "--fix"},
};

}  // namespace

std::vector<std::string> flags_of(const std::string& field) {
  std::vector<std::string> flags;
  const std::string quoted = "`" + field + "`";
  for (const auto& [f, flag] : kFlags)
    if (quoted == f) flags.push_back(flag);
  return flags;
}

std::string with_flags(std::string message) {
  for (const auto& [field, flag] : kFlags)
    for (std::size_t at = message.find(field); at != std::string::npos;
         at = message.find(field, at))
      message.replace(at, std::string(field).size(), flag);
  return message;
}
