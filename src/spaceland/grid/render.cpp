// The probe grid as a 3D method: voxelise, solve (once per bounce), shade the camera's pixels and
// the fog on their rays.
#include <algorithm>
#include <any>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
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
#include "spaceland/sky.hpp"
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
  // What its voxels are made from (voxel_key): a grid for the same scene and plan lit otherwise
  // (the sun, the sky) shares them where no bounce lit them.
  std::uint64_t voxel_key = 0;
  std::shared_ptr<Clipmap> map;
  bool own_voxels = false;  // made for this grid, not shared from the one before
  LevelFields field;
  GridOptions used;
  std::uint64_t voxel_bytes = 0, memory_bytes = 0;
};

// Feeds `f` where the levels lie.
void hash_plan(Fnv1a& f, const std::vector<ClipLevel>& plan) {
  for (const ClipLevel& l : plan) {
    f.value(l.size);
    f.value(l.box.first);
    f.value(l.box.dims);
    f.value(l.cut);
  }
}

// What a solved grid is made from: the scene but its camera, and its sun only where a later
// bounce lights the voxels with it (the cascades see the sky without the sun's disk; each pixel
// takes the sun through its own shadow ray), so that a sun moved with one bounce keeps the grid.
std::uint64_t kept_key(const SolveContext& ctx, const GridOptions& o,
                       const std::vector<ClipLevel>& plan) {
  Fnv1a f;
  f.value(ctx.kept->geometry_key);
  hash_light(f, ctx.scene, ctx.bounces > 1);
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
  hash_plan(f, plan);
  return f.h;
}

// What a grid's voxels are made from: the scene without its sky and sun, its dimming, the
// levels' placement and what the voxelising and the bounces' buffers depend on.
std::uint64_t voxel_key(const SolveContext& ctx, const GridOptions& o,
                        const std::vector<ClipLevel>& plan) {
  Fnv1a f;
  f.value(ctx.kept->geometry_key);
  f.value(ctx.light_exponent);
  f.value(spread_voxels(o));
  f.value(ctx.bounces > 1);
  hash_plan(f, plan);
  return f.h;
}

// The solve of a grid, a slab at a time: voxelise the planned levels, then solve their cascades
// once per bounce (CascadeSolve, level by level), lighting the voxels with the last bounce's
// fields before the next. advance() does as many slabs as it is given; voxelising and each
// lighting count as one. What it reads of the scene comes from each call's context: the voxels
// and sphere lights from the first call's, the sky and the sun (the bounces' light) from each
// call's, so a solve that goes on while the sun moves mixes the two (it is shown only until the
// next solve, from the view then, ends).
class GridSolve {
 public:
  // `reuse`: voxels made from the same scene and plan, not lit by bounces (the grid shown's,
  // shared), to solve over instead of voxelising again.
  GridSolve(std::uint64_t key, std::uint64_t voxel_key, std::vector<ClipLevel> plan, int bounces,
            float narrowest, std::shared_ptr<Clipmap> reuse)
      : plan_(std::move(plan)),
        bounces_(bounces),
        narrowest_(narrowest),
        reuse_(bounces == 1 ? std::move(reuse) : nullptr) {
    out_ = std::make_shared<KeptGrid>();
    out_->key = key;
    out_->voxel_key = voxel_key;
  }

  bool done() const { return done_; }
  // Slabs done and in all (known once voxelised: 1 before).
  std::uint64_t slabs_done() const { return done_slabs_; }
  std::uint64_t slabs() const { return slabs_; }
  const std::shared_ptr<KeptGrid>& grid() const { return out_; }

  Status advance(const SolveContext& ctx, const GridOptions& o, const Background& bg,
                 const SunLight& sun, std::uint64_t budget, SolveReport& report) {
    KeptGrid& out = *out_;
    while (budget > 0 && !done_) {
      Stopwatch watch;
      if (!voxelised_) {
        if (reuse_) {
          out.map = std::move(reuse_);  // the grid shown's voxels, unlit: this scene's
        } else {
          Expected<Clipmap> built =
              Clipmap::build(ctx.scene, std::move(plan_), ctx.max_memory / 4, spread_voxels(o));
          if (!built) return built.error();
          out.map = std::make_shared<Clipmap>(std::move(*built));
          out.own_voxels = true;
        }
        Clipmap& map = *out.map;
        out.used.voxel = map[0].size;
        out.used.levels = int(map.size());
        lights_ = map.lights(ctx.scene);
        out.voxel_bytes = voxel_bytes(map.voxels(), bounces_ > 1);
        left_ = ctx.max_memory - std::min(ctx.max_memory, out.voxel_bytes);
        if (bounces_ > 1) base_ = map.emission();
        slabs_ = 1 + std::uint64_t(bounces_ - 1);
        for (std::size_t l = 0; l < map.size(); ++l) {
          Expected<std::vector<CascadePlan>> p = plan_cascades(map[l], level_options(o, l));
          if (!p) return p.error();
          for (const CascadePlan& c : *p) slabs_ += std::uint64_t(c.nz) * std::uint64_t(bounces_);
        }
        voxelised_ = true;
        take(budget);
        if (out.own_voxels) report.stages.push_back({"voxelise", watch.ms()});
        continue;
      }
      const std::string stage = bounce_ == 0 ? "cascades" : "bounce " + std::to_string(bounce_ + 1);
      if (!solving_) {
        if (level_ == 0 && bounce_ > 0 && !lit_) {
          // The voxels lit by the last bounce's fields (the sun's light included), which then go.
          report.rays += add_bounces(*out.map, last_, base_, &sun);
          last_ = LevelFields{};
          lit_ = true;
          take(budget);
          report.stages.push_back({stage, watch.ms()});
          continue;
        }
        // The fields solved first hold part of what is left; this level's cascades the rest.
        const float narrowest = bounce_ + 1 == bounces_ ? narrowest_ : cascade::kInfinity;
        Expected<CascadeSolve> started =
            CascadeSolve::start((*out.map)[level_], level_options(o, level_),
                                left_ - std::min(left_, held_), &lights_[level_], narrowest);
        if (!started) return started.error();
        solving_.emplace(std::move(*started));
      }
      const std::uint64_t before = budget;
      const bool finished = solving_->step(bg, budget);
      done_slabs_ += before - budget;
      if (finished) {
        RadianceField f = solving_->finish();
        solving_.reset();
        report.rays += f.rays();
        held_ += f.bytes();
        fields_.map = out.map.get();
        fields_.fields.push_back(std::move(f));
        if (++level_ == out.map->size()) {
          if (bounce_ + 1 == bounces_) {
            finish(o);
          } else {  // the next bounce: these fields light the voxels first
            last_ = std::move(fields_);
            fields_ = LevelFields{};
            ++bounce_;
            level_ = 0;
            held_ = 0;
            lit_ = false;
          }
        }
      }
      // One stage per solve a frame takes part in, with its name.
      if (!report.stages.empty() && report.stages.back().name == stage)
        report.stages.back().ms += watch.ms();
      else
        report.stages.push_back({stage, watch.ms()});
    }
    return {};
  }

 private:
  void take(std::uint64_t& budget) {
    --budget;
    ++done_slabs_;
  }

  void finish(const GridOptions& o) {
    KeptGrid& out = *out_;
    out.field = std::move(fields_);
    out.field.map = out.map.get();
    const RadianceField& finest = out.field.fields[0];
    out.used.cascades = int(finest.cascades().size());
    out.used.interval = finest.cascades()[0].t_end;
    // The largest level's cascades while the others' fields are held.
    std::uint64_t fields = 0, cascades = 0;
    for (std::size_t l = 0; l < out.map->size(); ++l) {
      const RadianceField& f = out.field.fields[l];
      fields += f.bytes();
      const std::uint64_t solving = cascades_bytes(
          f.cascades(), level_options(o, l), (*out.map)[l].size, !lights_[l].empty(), f.cone_top());
      cascades = std::max(cascades, solving - std::min(solving, f.bytes()));
    }
    out.memory_bytes = out.voxel_bytes + fields + cascades;
    done_ = true;
  }

  std::shared_ptr<KeptGrid> out_;
  std::vector<ClipLevel> plan_;
  int bounces_ = 1;
  float narrowest_ = cascade::kInfinity;
  std::shared_ptr<Clipmap> reuse_;
  bool voxelised_ = false, lit_ = false, done_ = false;
  std::vector<cascade::SphereLights> lights_;
  std::vector<std::vector<Rgb>> base_;
  std::uint64_t left_ = 0, held_ = 0;
  int bounce_ = 0;
  std::size_t level_ = 0;
  std::optional<CascadeSolve> solving_;
  LevelFields fields_, last_;  // this bounce's fields solved so far; the last bounce's
  std::uint64_t done_slabs_ = 0, slabs_ = 1;
};

// What a Renderer keeps for the grid: the grid shown, and with temporal.grid_slabs the solve of
// the one the scene now asks for, under way.
struct GridState {
  std::shared_ptr<KeptGrid> shown;
  std::unique_ptr<GridSolve> pending;
};

}  // namespace

Expected<ImageRgb> render(const SolveContext& ctx, const GridOptions& o, SolveReport& report,
                          GridOptions& used) {
  // A quarter of the limit for the voxels, the rest for the cascades (and what render holds).
  std::vector<ClipLevel> plan =
      plan_levels(ctx.scene, o, ctx.max_memory / 4, ctx.bounces > 1, focus_distance(ctx.g));
  const Background bg(ctx.scene);
  const SunLight sun(ctx.scene, ctx.rays, ctx.sun_rays);
  // A Renderer's views share the solved grid while its levels stay where they are.
  using Shared = std::shared_ptr<GridState>;
  Shared* kept = ctx.kept ? std::any_cast<Shared>(&ctx.kept->method) : nullptr;
  GridState* state = kept ? kept->get() : nullptr;
  const std::uint64_t key = ctx.kept ? kept_key(ctx, o, plan) : 0;
  const std::uint64_t voxels = ctx.kept ? voxel_key(ctx, o, plan) : 0;
  // The grid shown's voxels, where this view's would be the same.
  std::shared_ptr<Clipmap> reuse =
      state && state->shown && state->shown->voxel_key == voxels ? state->shown->map : nullptr;
  // Kept while the memory the render allows holds what the solve needed (the voxels within a
  // quarter of it, as Clipmap::build asks, and everything within the whole), so that a render
  // would not have refused it.
  const auto fits = [&](const KeptGrid& k, std::uint64_t times) {
    return ctx.max_memory / times >= k.memory_bytes && ctx.max_memory / 4 / times >= k.voxel_bytes;
  };
  std::shared_ptr<KeptGrid> grid;
  const float narrowest = cascade::narrowest_lobe(ctx.scene);
  if (state && state->shown && state->shown->key == key && fits(*state->shown, 1)) {
    grid = state->shown;
    state->pending.reset();  // the view came back to the grid shown
  } else if (state && state->shown && ctx.grid_slabs > 0 && fits(*state->shown, 2)) {
    // The grid shown stays while the new one is solved, ctx.grid_slabs slabs a frame (the two
    // at once within the limit: the new one taken as large as the old). A solve under way goes
    // on to its end though the view has moved on since it began (a flying camera moves the
    // levels nearly every frame: starting again each time would never end); the next starts
    // from the view then.
    if (!state->pending)
      state->pending = std::make_unique<GridSolve>(key, voxels, std::move(plan), ctx.bounces,
                                                   narrowest, std::move(reuse));
    GridSolve& pending = *state->pending;
    if (Status s = pending.advance(ctx, o, bg, sun, ctx.grid_slabs, report); !s) {
      state->pending.reset();  // refused (the memory limit): the next frame starts again
      return s.error();
    }
    if (pending.done()) {
      state->shown = pending.grid();
      state->pending.reset();
    } else {
      report.grid_slabs_done = pending.slabs_done();
      report.grid_slabs = pending.slabs();
      if (pending.grid()->own_voxels) report.memory_bytes += pending.grid()->voxel_bytes;
    }
    grid = state->shown;
  } else {
    if (ctx.kept) ctx.kept->method.reset();  // the old grid goes before a new one is made
    GridSolve whole(key, voxels, std::move(plan), ctx.bounces, narrowest, std::move(reuse));
    if (Status s =
            whole.advance(ctx, o, bg, sun, std::numeric_limits<std::uint64_t>::max(), report);
        !s)
      return s.error();
    grid = whole.grid();
    if (ctx.kept) {
      auto fresh = std::make_shared<GridState>();
      fresh->shown = grid;
      ctx.kept->method = std::move(fresh);
    }
  }
  const Clipmap* map = grid->map.get();
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
