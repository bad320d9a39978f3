#include "spaceland/sun.hpp"

#include <cmath>
#include <limits>

#include "core/math.hpp"
#include "spaceland/color.hpp"
#include "spaceland/sky.hpp"

namespace penumbra::spaceland {

SunLight::SunLight(const Scene& scene, const RayScene& rays, int disk_rays)
    : rays_(&rays), media_(scene) {
  const Background bg(scene);
  on_ = bg.has_sun();
  if (!on_) return;
  dir_ = bg.sun_direction();
  irradiance_ = scene.sun.irradiance;
  if (disk_rays <= 1) return;
  // A golden-angle spiral over the disk's cap, each ray the centre of an equal solid angle: the
  // same directions at every point, so the penumbra is as smooth as their count, never noisy.
  const Vec3 t = normalize(cross(dir_, std::abs(dir_.x) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0}));
  const Vec3 b = cross(dir_, t);
  const double cos_a = std::cos(double(scene.sun.angular_radius) * kPi / 180);
  const double golden = kPi * (3 - std::sqrt(5.0));
  for (int i = 0; i < disk_rays; ++i) {
    const double z = 1 - (1 - cos_a) * (i + 0.5) / disk_rays;
    const double r = std::sqrt(std::max(0.0, 1 - z * z)), phi = golden * i;
    disk_.push_back(
        normalize(dir_ * float(z) + t * float(r * std::cos(phi)) + b * float(r * std::sin(phi))));
  }
}

Rgb SunLight::through_disk(Vec3 p, std::uint64_t& rays) const {
  if (disk_.empty()) return at(p, rays);
  int passed = 0;
  for (const Vec3& d : disk_) {
    ++rays;
    passed += !rays_->occluded(Ray{p, d, 0, std::numeric_limits<float>::infinity()});
  }
  if (passed == 0) return {};
  const Rgb e = irradiance_ * (float(passed) / float(disk_.size()));
  const Ray r{p, dir_, 0, std::numeric_limits<float>::infinity()};
  return media_.empty() ? e : e * media_.transmittance(r, r.tmax);
}

Rgb SunLight::at(Vec3 p, std::uint64_t& rays) const {
  ++rays;
  const Ray r{p, dir_, 0, std::numeric_limits<float>::infinity()};
  if (rays_->occluded(r)) return {};
  return media_.empty() ? irradiance_ : irradiance_ * media_.transmittance(r, r.tmax);
}

Rgb SunLight::reflected(const Hit& hit, Rgb albedo, std::uint64_t& rays) const {
  if (!on_ || !(dot(hit.geometric_normal, dir_) > 0)) return {};
  const float cos_s = dot(hit.shading_normal, dir_);
  if (!(cos_s > 0)) return {};
  return albedo * through_disk(rays_->spawn(hit.position, hit.geometric_normal, dir_), rays) *
         float(cos_s / kPi);
}

Rgb SunLight::reflected(Vec3 from, Vec3 n, Rgb albedo, std::uint64_t& rays) const {
  const float cos_s = dot(n, dir_);
  if (!on_ || !(cos_s > 0)) return {};
  return albedo * at(from, rays) * float(cos_s / kPi);
}

}  // namespace penumbra::spaceland
