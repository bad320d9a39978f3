// The sun as the cascades' renderers take it: exact shadow rays, at a visible hit spread over
// its disk (soft shadows), elsewhere one towards its centre (hard shadows).
#pragma once

#include <cstdint>
#include <vector>

#include "penumbra/spaceland/scene.hpp"
#include "spaceland/brdf.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/media.hpp"

namespace penumbra::spaceland {

// The sun's light reaching a point: its irradiance (normal to it) where one exact shadow ray
// towards its centre passes (hard shadows), times the fog's transmittance on the way. Each
// shadow ray traced is counted in `rays`.
class SunLight {
 public:
  // `disk_rays`: the shadow rays of reflected(Hit) over the sun's disk (1: towards its centre).
  SunLight(const Scene& scene, const RayScene& rays, int disk_rays = 1);
  bool on() const { return on_; }
  Vec3 direction() const { return dir_; }
  // The irradiance normal to the sun reaching free point p.
  Rgb at(Vec3 p, std::uint64_t& rays) const;
  // Reflected at a visible hit (normals faced to the camera): albedo / pi times the irradiance
  // of the part of the disk its disk_rays shadow rays find clear, each by its cosine.
  Rgb reflected(const Hit& hit, Rgb albedo, std::uint64_t& rays) const;
  // The same at a point with normal n, the shadow ray starting from `from` (already clear of
  // the surface).
  Rgb reflected(Vec3 from, Vec3 n, Rgb albedo, std::uint64_t& rays) const;
  // Reflected at a visible hit by a BRDF towards the viewer wo: the Lambertian's albedo as
  // above; a glossy one's value at the sun's centre (the sun is small) times what a white
  // Lambertian receives over pi over the cosine.
  Rgb reflected(const Hit& hit, const Brdf& brdf, Vec3 wo, std::uint64_t& rays) const;
  // The glossy BRDF's value from what reflected(hit, white) gave: one set of shadow rays for
  // both a glossy pixel's view and what a later bounce sees of it (its albedo times white).
  Rgb glossy(const Hit& hit, const Brdf& brdf, Vec3 wo, Rgb white) const;

 private:
  const RayScene* rays_;
  Media media_;
  bool on_ = false;
  Vec3 dir_{};
  Rgb irradiance_{};
  std::vector<Vec3> disk_;       // reflected(Hit)'s shadow rays; empty: one towards the centre
  float cos_a_ = 1, sin_a_ = 0;  // of the disk's angular radius
};

}  // namespace penumbra::spaceland
