// The G-buffer: each pixel's first hit along its camera ray, computed once and shared by every
// method that shades the visible surfaces (and written out by --aov).
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "core/parallel.hpp"
#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/camera.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/media.hpp"

namespace penumbra::spaceland {

// The albedo (texture included) and the emission of the surface at a hit.
Rgb albedo_at(const Scene& scene, const Hit& hit);
Rgb emission_at(const Scene& scene, const Hit& hit);

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

// Turns a hit's normals to the side the ray arrives from (surfaces are two-sided).
void face_towards(Hit& hit, Vec3 ray_direction);

struct GBuffer {
  int width = 0, height = 0;
  std::vector<Hit> hits;            // normals faced towards the camera
  std::vector<std::uint8_t> found;  // 1 where the camera ray hit a surface
  std::vector<Vec3> directions;     // unit camera ray of each pixel
  Vec3 forward;                     // the camera's view direction

  // Linear depth of pixel k's hit: its distance along the view direction.
  float linear_depth(std::size_t k) const { return hits[k].t * dot(directions[k], forward); }

  static std::uint64_t bytes_per_pixel() {
    return sizeof(Hit) + sizeof(std::uint8_t) + sizeof(Vec3);
  }
};

GBuffer make_gbuffer(const Scene& scene, const RayScene& rays);

// A G-buffer channel as an image (Aov::radiance is not one).
ImageRgb aov_image(const Scene& scene, const GBuffer& g, Aov aov);

// The camera's image shaded in parallel rows: a pixel that sees the sky shows `bg`, one that
// hits a surface shade(x, y, k, hit, rays) (k = y * width + x; `rays` counts the rays the
// shading traces, added to `traced`).
template <class Shade>
ImageRgb shade_pixels(const GBuffer& g, const Background& bg, std::uint64_t& traced,
                      Shade&& shade) {
  ImageRgb img(g.width, g.height);
  std::atomic<std::uint64_t> count{0};
  parallel_for(g.height, [&](int y) {
    std::uint64_t local = 0;
    for (int x = 0; x < g.width; ++x) {
      const std::size_t k = std::size_t(y) * std::size_t(g.width) + std::size_t(x);
      img.set(x, y, g.found[k] ? shade(x, y, k, g.hits[k], local) : bg(g.directions[k]));
    }
    count.fetch_add(local, std::memory_order_relaxed);
  });
  traced += count.load();
  return img;
}

}  // namespace penumbra::spaceland
