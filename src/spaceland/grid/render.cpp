// The probe grid as a 3D method: voxelise, solve (once per bounce), shade the camera's pixels and
// the fog on their rays.
#include <algorithm>
#include <any>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "core/fnv.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/brdf_albedo.hpp"
#include "spaceland/cascade/cone.hpp"
#include "spaceland/gbuffer.hpp"
#include "spaceland/grid/clipmap.hpp"
#include "spaceland/grid/grid.hpp"
#include "spaceland/media.hpp"
#include "spaceland/shade.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland::grid {

std::uint64_t estimate_bytes(const Scene& scene, const GridOptions& o, std::uint64_t max_memory,
                             bool bounces) {
  // Before the camera's first hits place the finest voxel: the finest it may be (the levels'
  // voxels grow to fit a quarter of the limit).
  const std::vector<ClipLevel> levels =
      plan_levels(scene, o, max_memory / 4, bounces, std::numeric_limits<float>::min());
  return std::uint64_t(std::min(double(voxel_bytes(1, bounces)) * clipmap_voxels(levels), 1.8e19));
}

namespace {

// The light reaching the camera along pixel k's ray: `behind` (what its hit, or the sky, sends)
// through the fog, plus what the fog emits and scatters towards the camera, integrated a step's
// length at a time (Beer-Lambert within each step, the in-scattered radiance at its middle).
Rgb through_fog(const Media& media, const LevelFields& field, const SunLight& sun, float step,
                Vec3 origin, Vec3 dir, float t_end, Rgb behind, std::vector<MediumPiece>& pieces,
                std::uint64_t& rays) {
  media.pieces(Ray{origin, dir, 0, t_end}, t_end, pieces);
  Rgb l{}, tr{1, 1, 1};
  for (const MediumPiece& piece : pieces) {
    const float len = piece.t1 - piece.t0;
    if (!(len > 0)) continue;
    const int steps = int(std::clamp(std::ceil(double(len) / step), 1.0, 4096.0));
    const float dt = len / float(steps);
    const Rgb& sigma = piece.sigma_t;
    const Rgb through = exp_neg(sigma * dt);
    for (int i = 0; i < steps; ++i) {
      const Vec3 x = origin + dir * (piece.t0 + (float(i) + 0.5f) * dt);
      const Rgb in = is_black(piece.sigma_s) ? Rgb{} : in_scattered(field, &sun, x, rays);
      l += tr * stretch_light(sigma, piece.emission + piece.sigma_s * in, dt, through);
      tr *= through;
    }
  }
  return l + tr * behind;
}

// The fog between the camera and what each pixel shows, a probe spacing a step (the
// in-scattered light's own resolution), over the image of the surfaces behind it.
std::uint64_t add_fog(const SolveContext& ctx, const LevelFields& field, const SunLight& sun,
                      float step, ImageRgb& img) {
  const Media media(ctx.scene);
  if (media.empty()) return 0;
  const GBuffer& g = ctx.g;
  std::atomic<std::uint64_t> traced{0};
  parallel_for(g.height, [&](int y) {
    std::vector<MediumPiece> pieces;
    std::uint64_t local = 0;
    for (int x = 0; x < g.width; ++x) {
      const std::size_t k = std::size_t(y) * std::size_t(g.width) + std::size_t(x);
      const float t_end = g.found[k] ? g.hits[k].t : cascade::kInfinity;
      img.set(x, y,
              through_fog(media, field, sun, step, ctx.scene.camera.position, g.directions[k],
                          t_end, img.at(x, y), pieces, local));
    }
    traced.fetch_add(local, std::memory_order_relaxed);
  });
  return traced.load();
}

}  // namespace

Expected<LevelFields> solve_levels(const Clipmap& map, const Background& bg, const GridOptions& o,
                                   std::uint64_t left,
                                   const std::vector<cascade::SphereLights>& lights,
                                   float narrowest) {
  LevelFields out;
  out.map = &map;
  std::uint64_t held = 0;  // what the fields already solved hold
  for (std::size_t l = 0; l < map.size(); ++l) {
    Expected<RadianceField> f =
        solve(map[l], bg, level_options(o, l), left - std::min(left, held), &lights[l], narrowest);
    if (!f) return f.error();
    held += f->bytes();
    out.fields.push_back(std::move(*f));
  }
  return out;
}

std::uint64_t add_bounces(Clipmap& map, const LevelFields& fields,
                          const std::vector<std::vector<Rgb>>& base, const SunLight* sun,
                          std::vector<std::vector<Vec3>>* normals) {
  std::uint64_t rays = 0;
  for (std::size_t l = 0; l < map.size(); ++l)
    rays += add_bounce(map[l], fields.fields[l], base[l], sun, normals ? &(*normals)[l] : nullptr);
  return rays;
}

namespace {

// What a Renderer keeps of the grid between views: the voxels and their solved cascades, for as
// long as the levels' placement (and everything else they are made from) stays the same; a
// level moves only when the camera crosses into another of its voxels' positions, or the finest
// voxel the view asks for changes. Shared: the clipmap's levels point to each other.
struct KeptGrid {
  std::uint64_t key = 0;
  Clipmap map;
  LevelFields field;
  GridOptions used;
  std::uint64_t voxel_bytes = 0, memory_bytes = 0;
};

std::uint64_t kept_key(const SolveContext& ctx, const GridOptions& o,
                       const std::vector<ClipLevel>& plan) {
  Fnv1a f;
  f.value(ctx.kept->scene_key);
  f.value(o.voxel);
  f.value(o.levels);
  f.value(o.probe_spacing);
  f.value(o.directions);
  f.value(o.interval);
  f.value(o.cascades);
  f.value(o.extend_length);
  f.value(o.fix);
  f.value(o.specular);
  f.value(ctx.bounces);
  f.value(ctx.light_exponent);
  f.value(ctx.sun_rays);
  for (const ClipLevel& l : plan) {
    f.value(l.size);
    f.value(l.box.first);
    f.value(l.box.dims);
    f.value(l.cut);
  }
  return f.h;
}

// Voxelises the planned levels and solves their cascades, once per bounce.
Status solve_grid(const SolveContext& ctx, const GridOptions& o, std::vector<ClipLevel> plan,
                  const Background& bg, const SunLight& sun, KeptGrid& out, SolveReport& report) {
  Stopwatch watch;
  const bool bounces = ctx.bounces > 1;
  Expected<Clipmap> built =
      Clipmap::build(ctx.scene, std::move(plan), ctx.max_memory / 4, spread_voxels(o));
  if (!built) return built.error();
  out.map = std::move(*built);
  Clipmap* map = &out.map;
  report.stages.push_back({"voxelise", watch.ms()});
  out.used.voxel = (*map)[0].size;
  out.used.levels = int(map->size());
  watch.restart();
  const std::uint64_t voxel_memory = voxel_bytes(map->voxels(), bounces);
  const std::uint64_t left = ctx.max_memory - std::min(ctx.max_memory, voxel_memory);
  const std::vector<cascade::SphereLights> lights = map->lights(ctx.scene);
  // The cone query reads the last solve's cascades only: earlier ones light the voxels.
  const float narrowest = cascade::narrowest_lobe(ctx.scene);
  Expected<LevelFields> field =
      solve_levels(*map, bg, o, left, lights, bounces ? cascade::kInfinity : narrowest);
  if (!field) return field.error();
  report.rays += field->rays();
  report.stages.push_back({"cascades", watch.ms()});
  // Later bounces: the surfaces' and the fog's own emission plus what the last field (and the
  // sun) brings them, solved again (the voxels' light after b bounces gives the pixels b + 1).
  if (bounces) {
    const std::vector<std::vector<Rgb>> base = map->emission();
    for (int b = 1; b < ctx.bounces; ++b) {
      watch.restart();
      report.rays += add_bounces(*map, *field, base, &sun);
      *field = LevelFields{};  // their radiance freed before the next solve's
      field = solve_levels(*map, bg, o, left, lights,
                           b + 1 == ctx.bounces ? narrowest : cascade::kInfinity);
      if (!field) return field.error();
      report.rays += field->rays();
      report.stages.push_back({"bounce " + std::to_string(b + 1), watch.ms()});
    }
  }
  out.field = std::move(*field);
  const RadianceField& finest = out.field.fields[0];
  out.used.cascades = int(finest.cascades().size());
  out.used.interval = finest.cascades()[0].t_end;
  out.voxel_bytes = voxel_memory;
  // The largest level's cascades while the others' fields are held.
  std::uint64_t fields = 0, cascades = 0;
  for (std::size_t l = 0; l < map->size(); ++l) {
    const RadianceField& f = out.field.fields[l];
    fields += f.bytes();
    const std::uint64_t solving = cascades_bytes(f.cascades(), level_options(o, l), (*map)[l].size,
                                                 !lights[l].empty(), f.cone_top());
    cascades = std::max(cascades, solving - std::min(solving, f.bytes()));
  }
  out.memory_bytes = voxel_memory + fields + cascades;
  return {};
}

}  // namespace

Expected<ImageRgb> render(const SolveContext& ctx, const GridOptions& o, SolveReport& report,
                          GridOptions& used) {
  // A quarter of the limit for the voxels, the rest for the cascades (and what render holds).
  std::vector<ClipLevel> plan =
      plan_levels(ctx.scene, o, ctx.max_memory / 4, ctx.bounces > 1, focus_distance(ctx.g));
  const Background bg(ctx.scene);
  const SunLight sun(ctx.scene, ctx.rays, ctx.sun_rays);
  // A Renderer's views share the solved grid while its levels stay where they are.
  using Shared = std::shared_ptr<KeptGrid>;
  const Shared* kept = ctx.kept ? std::any_cast<Shared>(&ctx.kept->method) : nullptr;
  const std::uint64_t key = ctx.kept ? kept_key(ctx, o, plan) : 0;
  Shared grid;
  // Kept while the memory the render allows holds what the solve needed (the voxels within a
  // quarter of it, as Clipmap::build asks, and everything within the whole), so that a render
  // would not have refused it.
  if (kept && *kept && (*kept)->key == key && ctx.max_memory >= (*kept)->memory_bytes &&
      ctx.max_memory / 4 >= (*kept)->voxel_bytes) {
    grid = *kept;
  } else {
    if (ctx.kept) ctx.kept->method.reset();  // the old grid goes before a new one is made
    grid = std::make_shared<KeptGrid>();
    grid->key = key;
    if (Status s = solve_grid(ctx, o, std::move(plan), bg, sun, *grid, report); !s)
      return s.error();
    if (ctx.kept) ctx.kept->method = grid;
  }
  const Clipmap* map = &grid->map;
  const LevelFields* field = &grid->field;
  // Far geometry makes the levels' voxels grow until the last holds the scene: near the camera
  // the grid then resolves nothing, silently (a sphere 1e17 away took the indirect light).
  const float wanted = focus_distance(ctx.g) / kFocusVoxels;
  if (o.voxel == 0 && wanted > 0 && (*map)[0].size > 8 * wanted)
    report.warnings.push_back(
        "the probe grid's finest voxel is " + io::format_number((*map)[0].size) + ", " +
        io::format_rounded((*map)[0].size / wanted) + " times what the view asks for (" +
        io::format_number(wanted) +
        "): the scene is too large for the grid's levels to reach from the camera, so light "
        "within a voxel of the surfaces seen is lost; leave the far geometry out or use spwi");
  used.voxel = grid->used.voxel;
  used.levels = grid->used.levels;
  used.cascades = grid->used.cascades;
  used.interval = grid->used.interval;
  report.voxel_bytes = grid->voxel_bytes;
  report.memory_bytes += grid->memory_bytes;
  Stopwatch watch;

  ImageRgb img = shade_pixels(
      ctx.g, bg, report.rays, [&](int, int, std::size_t k, const Hit& h, std::uint64_t& local) {
        const Brdf brdf = brdf_at(ctx.scene, h);
        const Vec3 wo = normalize(-ctx.g.directions[k]);
        // The Lambertian: its albedo and no specular lobe.
        const LobeAlbedo lobes = lobe_albedo(brdf, std::max(dot(h.shading_normal, wo), 0.0f));
        Rgb l = emission_at(ctx.scene, h), mean;
        if (field->mean_radiance(h.position, h.geometric_normal, mean, &ctx.rays))
          l += lobes.diffuse * mean;
        if (!brdf.lambertian &&
            field->lobe_radiance(h.position, h.geometric_normal, h.shading_normal, wo, brdf.alpha,
                                 mean, &ctx.rays))
          l += lobes.specular * mean;
        return l + sun.reflected(h, brdf, wo, local);
      });
  report.rays += add_fog(ctx, *field, sun, used.voxel * float(o.probe_spacing), img);
  report.stages.push_back({"gather", watch.ms()});
  return img;
}

}  // namespace penumbra::spaceland::grid
