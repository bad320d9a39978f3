// The sun as the cascades' renderers take it: one exact shadow ray per point (hard shadows).
#pragma once

#include <cstdint>

#include "penumbra/spaceland/scene.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/media.hpp"

namespace penumbra::spaceland {

// The sun's light reaching a point: its irradiance (normal to it) where one exact shadow ray
// towards its centre passes (hard shadows), times the fog's transmittance on the way. Each
// shadow ray traced is counted in `rays`.
class SunLight {
 public:
  SunLight(const Scene& scene, const RayScene& rays);
  bool on() const { return on_; }
  Vec3 direction() const { return dir_; }
  // The irradiance normal to the sun reaching free point p.
  Rgb at(Vec3 p, std::uint64_t& rays) const;
  // Reflected at a visible hit (normals faced to the camera): albedo E cos / pi, 0 where the
  // surface faces away or the shadow ray is blocked.
  Rgb reflected(const Hit& hit, Rgb albedo, std::uint64_t& rays) const;
  // The same at a point with normal n, the shadow ray starting from `from` (already clear of
  // the surface).
  Rgb reflected(Vec3 from, Vec3 n, Rgb albedo, std::uint64_t& rays) const;

 private:
  const RayScene* rays_;
  Media media_;
  bool on_ = false;
  Vec3 dir_{};
  Rgb irradiance_{};
};

}  // namespace penumbra::spaceland
