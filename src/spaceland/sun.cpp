#include "spaceland/sun.hpp"

#include <limits>

#include "core/math.hpp"
#include "spaceland/color.hpp"
#include "spaceland/sky.hpp"

namespace penumbra::spaceland {

SunLight::SunLight(const Scene& scene, const RayScene& rays) : rays_(&rays), media_(scene) {
  const Background bg(scene);
  on_ = bg.has_sun();
  if (!on_) return;
  dir_ = bg.sun_direction();
  irradiance_ = scene.sun.irradiance;
}

Rgb SunLight::at(Vec3 p, std::uint64_t& rays) const {
  ++rays;
  const Ray r{p, dir_, 0, std::numeric_limits<float>::infinity()};
  if (rays_->occluded(r)) return {};
  return media_.empty() ? irradiance_ : irradiance_ * media_.transmittance(r, r.tmax);
}

Rgb SunLight::reflected(const Hit& hit, Rgb albedo, std::uint64_t& rays) const {
  if (!on_ || !(dot(hit.geometric_normal, dir_) > 0)) return {};
  return reflected(rays_->spawn(hit.position, hit.geometric_normal, dir_), hit.shading_normal,
                   albedo, rays);
}

Rgb SunLight::reflected(Vec3 from, Vec3 n, Rgb albedo, std::uint64_t& rays) const {
  const float cos_s = dot(n, dir_);
  if (!on_ || !(cos_s > 0)) return {};
  return albedo * at(from, rays) * float(cos_s / kPi);
}

}  // namespace penumbra::spaceland
