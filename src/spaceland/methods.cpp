// The table of 3D methods (spaceland/method.hpp): each method's options, checks, memory estimate,
// description and solve.
#include <cmath>
#include <cstdio>
#include <iterator>
#include <string>

#include "io/json_reader.hpp"
#include "spaceland/atlas/render.hpp"
#include "spaceland/cascade/cone.hpp"
#include "spaceland/grid/grid.hpp"
#include "spaceland/method.hpp"
#include "spaceland/pt/pt.hpp"
#include "spaceland/radiance_cache.hpp"
#include "spaceland/spwi/spwi.hpp"
#include "spaceland/ssrc/gpu.hpp"
#include "spaceland/ssrc/ssrc.hpp"

namespace penumbra::spaceland {
namespace {

bool always(const RenderOptions&) {
  return true;
}
bool never(const RenderOptions&) {
  return false;
}

// The cascade parameters SPWI and the grid share, as used.
template <class Cascades>
void cascade_parameters(const Cascades& m, std::vector<Parameter>& p) {
  p.push_back({"probe_spacing", std::int64_t(m.probe_spacing)});
  p.push_back({"directions", std::int64_t(m.directions)});
  p.push_back({"interval", double(m.interval)});
  p.push_back({"cascades", std::int64_t(m.cascades)});
}

// ---- pt: the reference path tracer ----

constexpr const char* kPtOptions[] = {"pt.spp", "pt.seconds", "pt.seed"};

Status pt_check(const RenderOptions& o) {
  if (o.pt.spp < 0)
    return Error{"`pt.spp`: expected a count >= 0, found " + std::to_string(o.pt.spp)};
  if (!std::isfinite(o.pt.seconds) || o.pt.seconds < 0)
    return Error{"`pt.seconds`: expected a number of seconds >= 0, found " +
                 io::format_number(o.pt.seconds)};
  if (o.pt.spp == 0 && o.pt.seconds == 0)
    return Error{
        "`pt.spp` is 0 (no limit) and no `pt.seconds` is given: the render would "
        "never end"};
  return {};
}

std::uint64_t pt_bytes(const Scene& scene, const RenderOptions&) {
  return pt::working_bytes(scene.camera.width, scene.camera.height);
}

void pt_describe(const RenderResult& r, std::vector<Parameter>& p, std::string& line) {
  const PtOptions& o = r.options.pt;
  p.push_back({"spp", std::int64_t(o.spp)});
  p.push_back({"time", o.seconds});
  p.push_back({"seed", o.seed});
  line = ", " + std::to_string(r.samples) + " samples per pixel, " +
         std::to_string(r.options.bounces) + (r.options.bounces == 1 ? " bounce" : " bounces");
}

Expected<ImageRgb> pt_solve(const SolveContext& ctx, const RenderOptions& o, SolveReport& report,
                            RenderOptions&) {
  return pt::render(ctx, o.pt, report);
}

// ---- spwi: screen-space probes with world-space intervals (seed 000) ----

// With the grid's voxel size and levels and the cache's probe spacing: those of the radiance
// cache its later bounces read.
constexpr const char* kSpwiOptions[] = {
    "spwi.probe_spacing", "spwi.directions",     "spwi.interval",   "spwi.branching",
    "spwi.cascades",      "spwi.merge",          "spwi.sun",        "spwi.gather",
    "spwi.depth_bias",    "spwi.overlap",        "spwi.preaverage", "spwi.merge_edge",
    "spwi.gather_edge",   "spwi.gather_normal",  "spwi.specular",   "grid.voxel",
    "grid.levels",        "cache_probe_spacing", "sun_rays"};

Status spwi_check(const RenderOptions& o) {
  return spwi::check_options(o.spwi);
}

Status spwi_check_scene(const Scene& scene) {
  return spwi::check_scene(scene);
}

std::uint64_t spwi_bytes(const Scene& scene, const RenderOptions& o) {
  return spwi::bytes_upper_bound(scene, o.spwi);
}

void spwi_describe(const RenderResult& r, std::vector<Parameter>& p, std::string& line) {
  const SpwiOptions& o = r.options.spwi;
  cascade_parameters(o, p);
  p.push_back({"branching", std::int64_t(o.branching)});
  p.push_back({"merge", std::string(to_string(o.merge))});
  p.push_back({"sun", std::string(to_string(o.sun))});
  p.push_back({"gather", std::string(to_string(o.gather))});
  p.push_back({"depth_bias", double(o.depth_bias)});
  p.push_back({"overlap", o.overlap});
  p.push_back({"preaverage", o.preaverage});
  p.push_back({"merge_edge", double(o.merge_edge)});
  p.push_back({"gather_edge", double(o.gather_edge)});
  p.push_back({"gather_normal", double(o.gather_normal)});
  p.push_back({"specular", std::string(to_string(o.specular))});
  p.push_back({"sun_rays", std::int64_t(r.options.sun_rays)});
  if (r.options.bounces > 1 && r.options.aov == Aov::radiance) {
    // The radiance cache of its later bounces.
    p.push_back({"cache_voxel", double(r.options.grid.voxel)});
    p.push_back({"cache_levels", std::int64_t(r.options.grid.levels)});
    p.push_back({"cache_probe_spacing", std::int64_t(r.options.cache_probe_spacing)});
  }
  line = ", " + std::to_string(o.cascades) + " cascades, t0 " + io::format_rounded(o.interval) +
         ", merge " + to_string(o.merge) + ", sun " + to_string(o.sun);
  if (r.options.bounces > 1 && r.options.aov == Aov::radiance)
    line += ", cache voxel " + io::format_rounded(r.options.grid.voxel) +
            (r.options.grid.levels > 1 ? " in " + std::to_string(r.options.grid.levels) + " levels"
                                       : std::string());
}

Expected<ImageRgb> spwi_solve(const SolveContext& ctx, const RenderOptions& o, SolveReport& report,
                              RenderOptions& used) {
  spwi::Layout layout = spwi::make_layout(ctx.scene, ctx.g, o.spwi);
  spwi::shift_lattice(layout, ctx.frame);
  used.spwi.interval = layout.levels.t0;
  used.spwi.cascades = layout.count();
  used.spwi.probe_spacing = layout.levels.spacing0;
  return spwi::render(ctx, o.spwi, layout, report);
}

// ---- grid: the world-space probe grid (seed 001 4.3) ----

constexpr const char* kGridOptions[] = {
    "grid.voxel",    "grid.levels",        "grid.probe_spacing", "grid.directions", "grid.interval",
    "grid.cascades", "grid.extend_length", "grid.fix",           "grid.specular",   "sun_rays"};

Status grid_check(const RenderOptions& o) {
  return grid::check_options(o.grid);
}

std::uint64_t grid_bytes(const Scene& scene, const RenderOptions& o) {
  // The voxels; the cascades' share is checked when they are planned (the grid's size is known
  // only once the voxel size is).
  return grid::estimate_bytes(scene, o.grid, o.max_memory, o.bounces > 1);
}

void grid_describe(const RenderResult& r, std::vector<Parameter>& p, std::string& line) {
  const GridOptions& o = r.options.grid;
  cascade_parameters(o, p);
  p.push_back({"voxel", double(o.voxel)});
  p.push_back({"levels", std::int64_t(o.levels)});
  p.push_back({"voxel_memory_bytes", r.voxel_bytes});
  p.push_back({"extend_length", double(o.extend_length)});
  p.push_back({"fix", std::string(o.fix ? "bilinear" : "none")});
  p.push_back({"specular", std::string(to_string(o.specular))});
  p.push_back({"sun_rays", std::int64_t(r.options.sun_rays)});
  char mib[32];
  std::snprintf(mib, sizeof mib, "%.1f", double(r.voxel_bytes) / (1 << 20));
  line = ", voxel " + io::format_rounded(o.voxel) +
         (o.levels > 1 ? " in " + std::to_string(o.levels) + " levels" : std::string()) + " (" +
         mib + " MiB of voxels), " + std::to_string(o.cascades) + " cascades, t0 " +
         io::format_rounded(o.interval);
}

Expected<ImageRgb> grid_solve(const SolveContext& ctx, const RenderOptions& o, SolveReport& report,
                              RenderOptions& used) {
  return grid::render(ctx, o.grid, report, used.grid);
}

// ---- ssrc: screen-space radiance cascades (seed 001 section 4.2) ----

// On screen it marches the last bounce's image; rays going on through the world (--offscreen
// world) read the light the surfaces off screen reflect from the radiance cache.
bool ssrc_bounces_itself(const RenderOptions& o) {
  return o.ssrc.offscreen != SsrcOffscreen::world;
}

constexpr const char* kSsrcOptions[] = {"ssrc.probe_spacing",
                                        "ssrc.directions",
                                        "ssrc.interval",
                                        "ssrc.cascades",
                                        "ssrc.steps",
                                        "ssrc.backfaces",
                                        "ssrc.sectors",
                                        "ssrc.rays",
                                        "ssrc.thickness",
                                        "ssrc.merge",
                                        "ssrc.merge_edge",
                                        "ssrc.gather",
                                        "ssrc.gather_edge",
                                        "ssrc.gather_normal",
                                        "ssrc.offscreen",
                                        "ssrc.specular",
                                        "sun_rays"};

Status ssrc_check(const RenderOptions& o) {
  if (o.device == Device::gpu)
    if (Status s = ssrc::check_gpu_options(o.ssrc); !s) return s;
  return ssrc::check_options(o.ssrc);
}

Status ssrc_check_scene(const Scene& scene) {
  return ssrc::check_scene(scene);
}

std::uint64_t ssrc_bytes(const Scene& scene, const RenderOptions& o) {
  ssrc::Layout l = ssrc::make_layout(scene.camera.width, scene.camera.height, o.ssrc);
  l.glossy = cascade::any_glossy(scene);
  return l.bytes() + (o.device == Device::gpu ? ssrc::gpu_bytes(l, o.ssrc) : 0);
}

void ssrc_describe(const RenderResult& r, std::vector<Parameter>& p, std::string& line) {
  const SsrcOptions& o = r.options.ssrc;
  p.push_back({"probe_spacing", std::int64_t(o.probe_spacing)});
  p.push_back({"directions", std::int64_t(o.directions)});
  p.push_back({"interval", std::int64_t(o.interval)});
  p.push_back({"cascades", std::int64_t(o.cascades)});
  p.push_back({"steps", std::int64_t(o.steps)});
  p.push_back({"sectors", std::int64_t(o.sectors)});
  p.push_back({"rays", std::int64_t(o.rays)});
  p.push_back({"backfaces", o.backfaces});
  p.push_back({"thickness", double(o.thickness)});
  p.push_back({"merge", std::string(to_string(o.merge))});
  p.push_back({"merge_edge", double(o.merge_edge)});
  p.push_back({"gather", std::string(to_string(o.gather))});
  p.push_back({"gather_edge", double(o.gather_edge)});
  p.push_back({"gather_normal", double(o.gather_normal)});
  p.push_back({"offscreen", std::string(to_string(o.offscreen))});
  p.push_back({"specular", std::string(to_string(o.specular))});
  p.push_back({"sun_rays", std::int64_t(r.options.sun_rays)});
  line = ", " + std::to_string(o.cascades) + " cascades, s0 " + std::to_string(o.probe_spacing) +
         " px, r0 " + std::to_string(o.interval) + " px, " + std::to_string(o.sectors) +
         " sectors, " + std::to_string(o.steps) + " steps, " +
         (o.backfaces ? "back faces" : "thickness " + io::format_rounded(o.thickness)) +
         (o.offscreen == SsrcOffscreen::world ? ", off screen: world" : "");
}

// On the CPU, or with a port (the GPU's) running the cascades, the gather and the shading.
Expected<ImageRgb> ssrc_run(const SolveContext& ctx, const RenderOptions& o, SolveReport& report,
                            RenderOptions& used, ssrc::Port port) {
  ssrc::Layout layout = ssrc::make_layout(ctx.g.width, ctx.g.height, o.ssrc);
  layout.glossy = cascade::any_glossy(ctx.scene);
  layout.rotation = temporal::jitter(ctx.frame) * 2 * kPi / layout.q0;
  used.ssrc.probe_spacing = layout.tiles.levels.spacing0;
  used.ssrc.interval = layout.r0;
  used.ssrc.cascades = layout.count();
  return ssrc::render(ctx, o.ssrc, layout, report, port);
}

Expected<ImageRgb> ssrc_solve(const SolveContext& ctx, const RenderOptions& o, SolveReport& report,
                              RenderOptions& used) {
  return ssrc_run(ctx, o, report, used, nullptr);
}

Expected<ImageRgb> ssrc_solve_gpu(const SolveContext& ctx, const RenderOptions& o,
                                  SolveReport& report, RenderOptions& used) {
  return ssrc_run(ctx, o, report, used, ssrc::render_gpu);
}

// ---- surface: surface radiance cascades (seed 001 section 2.5.3) ----

constexpr const char* kSurfaceOptions[] = {
    "surface.texel_size", "surface.texels",   "surface.refine",
    "surface.directions", "surface.interval", "surface.cascades",
    "surface.atlas",      "surface.specular", "sun_rays"};

Status surface_check(const RenderOptions& o) {
  return atlas::check_options(o.surface);
}

Status surface_check_scene(const Scene& scene) {
  return atlas::check_scene(scene);
}

std::uint64_t surface_bytes(const Scene& scene, const RenderOptions& o) {
  return atlas::working_bytes(scene, o.surface);
}

void surface_describe(const RenderResult& r, std::vector<Parameter>& p, std::string& line) {
  const SurfaceOptions& o = r.options.surface;
  p.push_back({"texel_size", double(o.texel_size)});
  p.push_back({"texels", std::int64_t(o.texels)});
  p.push_back({"refine", std::int64_t(o.refine)});
  p.push_back({"directions", std::int64_t(o.directions)});
  p.push_back({"interval", double(o.interval)});
  p.push_back({"cascades", std::int64_t(o.cascades)});
  p.push_back({"specular", std::string(to_string(o.specular))});
  p.push_back({"sun_rays", std::int64_t(r.options.sun_rays)});
  if (!o.atlas.empty()) p.push_back({"atlas", o.atlas});
  line = (o.atlas.empty() ? std::string() : ", from " + o.atlas) + ", " +
         std::to_string(o.cascades) + " cascades, texel " + io::format_rounded(o.texel_size) +
         ", Q0 " + std::to_string(o.directions) + ", t0 " + io::format_rounded(o.interval);
}

Expected<ImageRgb> surface_solve(const SolveContext& ctx, const RenderOptions& o,
                                 SolveReport& report, RenderOptions& used) {
  return atlas::render(ctx, o.surface, report, used.surface);
}

// In the order of the Method enum.
constexpr MethodEntry kMethods[] = {
    {Method::pt, "pt", "the path tracer",
     "reference path tracer (next event estimation + MIS, fog, Owen-scrambled Sobol points)",
     kPtOptions, always, pt_check, nullptr, pt_bytes, pt_describe, pt_solve, nullptr},
    {Method::spwi, "spwi", "screen-space probes with world-space intervals",
     "screen-space probes with world-space intervals (seed 000): radiance cascades on the "
     "G-buffer, later bounces from the probe grid's radiance cache",
     kSpwiOptions, never, spwi_check, spwi_check_scene, spwi_bytes, spwi_describe, spwi_solve,
     nullptr},
    {Method::grid, "grid", "the world-space probe grid",
     "the world-space probe grid (seed 001 4.3): radiance cascades over the scene's voxels, "
     "fog and light shafts, later bounces, the radiance cache spwi's come from",
     kGridOptions, always, grid_check, nullptr, grid_bytes, grid_describe, grid_solve, nullptr},
    {Method::ssrc, "ssrc", "the screen-space radiance cascades",
     "screen-space radiance cascades (seed 001 4.2): probes and intervals on the screen, filled "
     "by marching the depth buffer with an occlusion bitmask; sees only what is on screen",
     kSsrcOptions, ssrc_bounces_itself, ssrc_check, ssrc_check_scene, ssrc_bytes, ssrc_describe,
     ssrc_solve, ssrc_solve_gpu},
    {Method::surface, "surface", "the surface radiance cascades",
     "surface radiance cascades (seed 001 2.5.3): the light baked into a texture atlas of every "
     "surface by cascades on its texels, the camera's first hits looking it up",
     kSurfaceOptions, always, surface_check, surface_check_scene, surface_bytes, surface_describe,
     surface_solve, nullptr},
};
constexpr bool in_enum_order() {
  for (std::size_t i = 0; i < std::size(kMethods); ++i)
    if (std::size_t(kMethods[i].method) != i) return false;
  return std::size(kMethods) == std::size_t(Method::surface) + 1;
}
static_assert(in_enum_order(), "one entry per Method, indexed by the enum");

}  // namespace

std::span<const MethodEntry> method_table() {
  return kMethods;
}

const MethodEntry& entry(Method m) {
  return kMethods[std::size_t(m)];
}

}  // namespace penumbra::spaceland
