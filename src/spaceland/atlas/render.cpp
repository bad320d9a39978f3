#include "spaceland/atlas/render.hpp"

#include <cmath>
#include <string>

#include "core/math.hpp"
#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/atlas/cascades.hpp"
#include "spaceland/color.hpp"
#include "spaceland/shade.hpp"
#include "spaceland/sun.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland::atlas {
namespace {

// The side of an equal-area map holding `directions` directions; 0 where it is no square of a
// power of two in range.
int side_of(int directions) {
  for (int side = 2; side <= 64; side *= 2)
    if (side * side == directions) return side;
  return 0;
}

}  // namespace

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
  if (o.cascades < 0 || o.cascades > 12)
    return Error{"`surface.cascades`: expected 0..12, found " + std::to_string(o.cascades)};
  return {};
}

Status check_scene(const Scene& scene) {
  return refuse_fog(scene, "surface", "--method grid or pt");
}

std::uint64_t working_bytes(const Scene& scene, const SurfaceOptions& o) {
  double texels = double(o.texels);
  if (o.texel_size > 0) texels = surface_area(scene) / (double(o.texel_size) * o.texel_size);
  return bake_bytes(std::uint64_t(std::min(3 * texels, 1e15)), side_of(o.directions));
}

Expected<ImageRgb> render(const SolveContext& ctx, const SurfaceOptions& o, SolveReport& report,
                          SurfaceOptions& used) {
  Options ao;
  ao.texel_size = o.texel_size;
  ao.texels = o.texels;
  CascadeOptions co;
  co.side0 = side_of(o.directions);
  co.t0 = o.interval;
  co.cascades = o.cascades;
  co.bounces = ctx.bounces;

  BakeReport bake_report;
  Expected<Baked> baked = bake(ctx.scene, ctx.rays, ao, co, ctx.max_memory, bake_report);
  if (!baked) return baked.error();
  report.stages.insert(report.stages.end(), bake_report.stages.begin(), bake_report.stages.end());
  report.rays += bake_report.rays;
  report.memory_bytes += bake_report.memory_bytes;
  used.texel_size = baked->atlas.texel_size;
  used.interval = bake_report.t0;
  used.cascades = bake_report.cascades;

  Stopwatch watch;
  const Background bg(ctx.scene);
  const SunLight sun(ctx.scene, ctx.rays, ctx.sun_rays);
  ImageRgb img = shade_pixels(
      ctx.g, bg, report.rays, [&](int, int, std::size_t k, const Hit& h, std::uint64_t& local) {
        const Rgb albedo = albedo_at(ctx.scene, h);
        const Rgb e = baked->irradiance_at(ctx.scene, h, -ctx.g.directions[k], false);
        return emission_at(ctx.scene, h) + albedo * e * float(1 / kPi) +
               sun.reflected(h, albedo, local);
      });
  report.stages.push_back({"view", watch.ms()});
  return img;
}

}  // namespace penumbra::spaceland::atlas
