#include "spaceland/atlas/render.hpp"

#include <algorithm>
#include <any>
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/fnv.hpp"
#include "core/math.hpp"
#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/atlas/cascades.hpp"
#include "spaceland/atlas/file.hpp"
#include "spaceland/brdf_albedo.hpp"
#include "spaceland/cascade/cone.hpp"
#include "spaceland/cascade/store.hpp"
#include "spaceland/color.hpp"
#include "spaceland/shade.hpp"
#include "spaceland/sun.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland::atlas {

Status check_options(const SurfaceOptions& o) {
  if (!(o.texel_size >= 0) || !std::isfinite(o.texel_size))
    return Error{"`surface.texel_size`: expected a size >= 0 (0: from the texel budget), found " +
                 io::format_number(o.texel_size)};
  if (o.texels < 64 || o.texels > (std::uint64_t(1) << 28))
    return Error{"`surface.texels`: expected 64..268435456 texels, found " +
                 std::to_string(o.texels)};
  if (side_of(o.directions) == 0)
    return Error{"`surface.directions`: expected the square of a power of two in 4..4096, found " +
                 std::to_string(o.directions)};
  if (!(o.interval >= 0) || !std::isfinite(o.interval))
    return Error{"`surface.interval`: expected a length >= 0 (0: two texels), found " +
                 io::format_number(o.interval)};
  if (o.refine < 0 || o.refine > 10)
    return Error{"`surface.refine`: expected 0..10 levels, found " + std::to_string(o.refine)};
  if (o.cascades < 0 || o.cascades > 12)
    return Error{"`surface.cascades`: expected 0..12, found " + std::to_string(o.cascades)};
  if (o.specular != SpecularQuery::wide)
    return Error{std::string("`surface.specular`: expected wide (the widest query, over cascade "
                             "0's radiance kept per texel), found ") +
                 to_string(o.specular) +
                 ": the cone query over the surface cascades' own intervals is not built"};
  return {};
}

Status check_scene(const Scene& scene) {
  return refuse_fog(scene, "surface", "--method grid or pt");
}

std::uint64_t working_bytes(const Scene& scene, const SurfaceOptions& o, bool radiance) {
  if (!o.atlas.empty()) return 0;
  double texels = double(o.texels);
  if (o.texel_size > 0) texels = surface_area(scene) / (double(o.texel_size) * o.texel_size);
  texels = std::min(3 * texels, 1e15);
  std::uint64_t bytes = bake_bytes(std::uint64_t(texels), side_of(o.directions));
  // The bake's per-texel copy, the file's planar floats, their half copy and the encoding; a
  // glossy scene's view keeps the copy alone.
  const int copies = radiance ? 4 : cascade::any_glossy(scene) ? 1 : 0;
  bytes += std::uint64_t(copies) *
           cascade::RadianceStore::bytes(std::uint64_t(texels), side_of(o.directions));
  return bytes;
}

namespace {

Options atlas_options(const SurfaceOptions& o) {
  Options ao;
  ao.texel_size = o.texel_size;
  ao.texels = o.texels;
  ao.refine = o.refine;
  return ao;
}

CascadeOptions cascade_options(const SurfaceOptions& o, int bounces) {
  CascadeOptions co;
  co.side0 = side_of(o.directions);
  co.t0 = o.interval;
  co.cascades = o.cascades;
  co.bounces = bounces;
  return co;
}

// Every value of the baked light times 2^k (exact: powers of two move exponents only).
void scale(Baked& b, int k) {
  if (k == 0) return;
  for (std::vector<Rgb>* v : {&b.front, &b.back, &b.sun_front, &b.sun_back, &b.radiance})
    for (Rgb& x : *v) x = {std::ldexp(x.r, k), std::ldexp(x.g, k), std::ldexp(x.b, k)};
}

}  // namespace

Status bake_file(const FileBake& b, const std::string& path, BakeResult& result) {
  CascadeOptions co = cascade_options(b.o, b.bounces);
  co.keep_radiance = b.radiance;
  BakeReport report;
  Expected<Baked> baked = bake(b.scene, b.rays, atlas_options(b.o), co, b.max_bytes, report);
  if (!baked) return baked.error();
  Record r;
  r.light_exponent = b.light_exponent;
  r.scene_hash = scene_hash(b.given);
  r.texel_size = baked->atlas.texel_size;
  r.gutter = baked->atlas.gutter;
  r.refine = baked->atlas.refine;
  r.max_angle = Options{}.max_angle;
  r.directions = b.o.directions;
  r.interval = report.t0;
  r.cascades = report.cascades;
  r.bounces = b.bounces;
  Stopwatch watch;
  if (Status s = write_atlas(path, *baked, r); !s) return s;
  report.stages.push_back({"write", watch.ms()});

  result.used = b.o;
  result.used.texel_size = r.texel_size;
  result.used.refine = r.refine;
  result.used.interval = r.interval;
  result.used.cascades = r.cascades;
  result.width = baked->atlas.width;
  result.height = baked->atlas.height;
  result.charts = baked->atlas.charts.size();
  for (const Chart& c : baked->atlas.charts) result.lightmap_charts += c.from_lightmap ? 1 : 0;
  for (const Texel& t : baked->texels) result.covered += t.chart >= 0 ? 1 : 0;
  result.scene_hash = r.scene_hash;
  result.radiance = baked->side0 > 0;
  result.probes = report.probes;
  result.store_bytes = report.store_bytes;
  result.stages.insert(result.stages.end(), report.stages.begin(), report.stages.end());
  result.memory_bytes += report.memory_bytes;
  result.rays += report.rays;
  std::error_code ec;
  result.file_bytes = std::uint64_t(std::filesystem::file_size(path, ec));
  return {};
}

namespace {

// What a Renderer keeps of the surface method between views: the atlas, seams and walls linked,
// and what it was made from (the scene but its camera, the options, bounces and light scale).
struct KeptAtlas {
  std::uint64_t key = 0;
  Baked baked;
  SurfaceOptions used;
  std::uint64_t memory_bytes = 0;
};

std::uint64_t kept_key(const SolveContext& ctx, const SurfaceOptions& o, bool glossy) {
  Fnv1a f;
  f.value(ctx.kept->scene_key);
  f.value(o.texel_size);
  f.value(o.texels);
  f.value(o.refine);
  f.value(o.directions);
  f.value(o.interval);
  f.value(o.cascades);
  f.bytes(o.atlas.data(), o.atlas.size());
  if (!o.atlas.empty()) {  // a file baked again under the same name is read again
    std::error_code ec;
    f.value(std::filesystem::last_write_time(o.atlas, ec).time_since_epoch().count());
    f.value(std::filesystem::file_size(o.atlas, ec));
  }
  f.value(ctx.bounces);
  f.value(ctx.light_exponent);
  f.value(glossy);
  return f.h;
}

// Bakes (or reads o.atlas) and links its seams and walls.
Expected<Baked> make_baked(const SolveContext& ctx, const SurfaceOptions& o, bool glossy,
                           SolveReport& report, SurfaceOptions& used) {
  Expected<Baked> baked = Error{""};
  if (o.atlas.empty()) {
    BakeReport bake_report;
    CascadeOptions co = cascade_options(o, ctx.bounces);
    co.keep_radiance = glossy;
    baked = bake(ctx.scene, ctx.rays, atlas_options(o), co, ctx.max_memory, bake_report);
    if (!baked) return baked.error();
    report.stages.insert(report.stages.end(), bake_report.stages.begin(), bake_report.stages.end());
    report.rays += bake_report.rays;
    report.memory_bytes += bake_report.memory_bytes;
    used.texel_size = baked->atlas.texel_size;
    used.refine = baked->atlas.refine;
    used.interval = bake_report.t0;
    used.cascades = bake_report.cascades;
  } else {
    Stopwatch watch;
    Record r;
    baked = read_atlas(o.atlas, ctx.given ? *ctx.given : ctx.scene, ctx.max_memory, r, glossy,
                       ctx.bounces);
    if (!baked) return baked.error();
    if (glossy && baked->side0 == 0)
      return Error{"atlas " + o.atlas +
                   " holds no radiance per direction (baked with --no-radiance), which the "
                   "scene's glossy materials read: bake it again without --no-radiance"};
    // The file holds the light at 2^-k of its scale; the view runs at 2^-light_exponent.
    scale(*baked, r.light_exponent - ctx.light_exponent);
    report.stages.push_back({"read atlas", watch.ms()});
    report.memory_bytes += baked->texels.size() * (sizeof(Texel) + 4 * sizeof(Rgb)) +
                           baked->radiance.size() * sizeof(Rgb);
    used.texel_size = r.texel_size;
    used.refine = r.refine;
    used.directions = r.directions;
    used.interval = r.interval;
    used.cascades = r.cascades;
  }

  Stopwatch watch;
  link_seams(ctx.scene, ctx.rays, *baked);
  report.stages.push_back({"seams", watch.ms()});
  if (!o.atlas.empty()) {
    // A bake marked them; a file does not hold them.
    watch.restart();
    mark_walls(ctx.rays, *baked);
    report.stages.push_back({"walls", watch.ms()});
  }
  return baked;
}

}  // namespace

Expected<ImageRgb> render(const SolveContext& ctx, const SurfaceOptions& o, SolveReport& report,
                          SurfaceOptions& used) {
  // Glossy materials read cascade 0's radiance per direction: kept by the bake, read from a file.
  const bool glossy = cascade::any_glossy(ctx.scene);
  // A Renderer's views of one scene share the atlas: baked (or read) once.
  KeptAtlas* kept = ctx.kept ? std::any_cast<KeptAtlas>(&ctx.kept->method) : nullptr;
  const std::uint64_t key = ctx.kept ? kept_key(ctx, o, glossy) : 0;
  std::optional<Baked> own;
  const Baked* baked = nullptr;
  // Kept while the memory the render allows holds what the bake (or the read) needed, so that a
  // render would not have refused it.
  if (kept && kept->key == key && ctx.max_memory >= kept->memory_bytes) {
    baked = &kept->baked;
    report.memory_bytes += kept->memory_bytes;
    used = kept->used;
  } else {
    if (ctx.kept) ctx.kept->method.reset();  // the old atlas goes before a new one is made
    const std::uint64_t before = report.memory_bytes;
    Expected<Baked> made = make_baked(ctx, o, glossy, report, used);
    if (!made) return made.error();
    if (ctx.kept) {
      ctx.kept->method = KeptAtlas{key, std::move(*made), used, report.memory_bytes - before};
      baked = &std::any_cast<KeptAtlas>(&ctx.kept->method)->baked;
    } else {
      own = std::move(*made);
      baked = &*own;
    }
  }

  Stopwatch watch;
  const Background bg(ctx.scene);
  const SunLight sun(ctx.scene, ctx.rays, ctx.sun_rays);
  ImageRgb img = shade_pixels(
      ctx.g, bg, report.rays, [&](int, int, std::size_t k, const Hit& h, std::uint64_t& local) {
        const Brdf brdf = brdf_at(ctx.scene, h);
        const Vec3 wo = normalize(-ctx.g.directions[k]);
        // The Lambertian: its albedo and no specular lobe.
        const LobeAlbedo lobes = lobe_albedo(brdf, std::max(dot(h.shading_normal, wo), 0.0f));
        const Rgb e = baked->irradiance_at(ctx.scene, ctx.rays, h, wo, false);
        Rgb l = emission_at(ctx.scene, h) + lobes.diffuse * e * float(1 / kPi);
        if (!brdf.lambertian)
          l += lobes.specular *
               baked->lobe_at(ctx.scene, ctx.rays, h, wo, h.shading_normal, brdf.alpha);
        return l + sun.reflected(h, brdf, wo, local);
      });
  report.stages.push_back({"view", watch.ms()});
  return img;
}

}  // namespace penumbra::spaceland::atlas
