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
  const double a = double(scene.sun.angular_radius) * kPi / 180;
  cos_a_ = float(std::cos(a));
  sin_a_ = float(std::sin(a));
  const double golden = kPi * (3 - std::sqrt(5.0));
  for (int i = 0; i < disk_rays; ++i) {
    const double z = 1 - (1 - double(cos_a_)) * (i + 0.5) / disk_rays;
    const double r = std::sqrt(std::max(0.0, 1 - z * z)), phi = golden * i;
    disk_.push_back(
        normalize(dir_ * float(z) + t * float(r * std::cos(phi)) + b * float(r * std::sin(phi))));
  }
}

Rgb SunLight::at(Vec3 p, std::uint64_t& rays) const {
  ++rays;
  const Ray r{p, dir_, 0, std::numeric_limits<float>::infinity()};
  if (rays_->occluded(r)) return {};
  return media_.empty() ? irradiance_ : irradiance_ * media_.transmittance(r, r.tmax);
}

Rgb SunLight::reflected(const Hit& hit, Rgb albedo, std::uint64_t& rays) const {
  if (!on_) return {};
  if (disk_.empty()) {
    if (!(dot(hit.geometric_normal, dir_) > 0)) return {};
    return reflected(rays_->spawn(hit.position, hit.geometric_normal, dir_), hit.shading_normal,
                     albedo, rays);
  }
  // Each ray by its own cosine, none below the surface's horizon. A surface above which the whole
  // disk lies gets E cos (exact) times the clear rays' part of their cosines; one whose horizon
  // cuts the disk E 2 / (1 + cos a) times the clear rays' mean cosine (the rays' mean cosine to
  // the disk's centre is (1 + cos a) / 2).
  if (!(dot(hit.geometric_normal, dir_) > -sin_a_)) return {};
  const float inf = std::numeric_limits<float>::infinity();
  double clear = 0, all = 0;
  bool whole = true;
  for (const Vec3& d : disk_) {
    const float c = dot(hit.shading_normal, d);
    if (!(c > 0) || !(dot(hit.geometric_normal, d) > 0)) {
      whole = false;
      continue;
    }
    ++rays;
    all += double(c);
    if (!rays_->occluded(Ray{rays_->spawn(hit.position, hit.geometric_normal, d), d, 0, inf}))
      clear += double(c);
  }
  if (!(clear > 0)) return {};
  const double cos_s = double(dot(hit.shading_normal, dir_));
  const double part =
      whole ? cos_s * clear / all : 2 / (1 + double(cos_a_)) * clear / double(disk_.size());
  Rgb e = irradiance_ * float(part / kPi);
  if (!media_.empty()) {
    const Ray r{rays_->spawn(hit.position, hit.geometric_normal, dir_), dir_, 0, inf};
    e = e * media_.transmittance(r, r.tmax);
  }
  return albedo * e;
}

Rgb SunLight::reflected(const Hit& hit, const Brdf& brdf, Vec3 wo, std::uint64_t& rays) const {
  if (brdf.lambertian) return reflected(hit, brdf.diffuse, rays);
  const float cs = dot(hit.shading_normal, dir_);
  if (!on_ || !(cs > 0)) return {};
  return glossy(hit, brdf, wo, reflected(hit, Rgb{1, 1, 1}, rays));
}

Rgb SunLight::glossy(const Hit& hit, const Brdf& brdf, Vec3 wo, Rgb white) const {
  const float cs = dot(hit.shading_normal, dir_);
  if (!on_ || !(cs > 0)) return {};
  return white * brdf_cos(brdf, hit.shading_normal, hit.geometric_normal, wo, dir_) *
         float(kPi / cs);
}

Rgb SunLight::reflected(Vec3 from, Vec3 n, Rgb albedo, std::uint64_t& rays) const {
  const float cos_s = dot(n, dir_);
  if (!on_ || !(cos_s > 0)) return {};
  return albedo * at(from, rays) * float(cos_s / kPi);
}

}  // namespace penumbra::spaceland
