// The G-buffer: each pixel's first hit along its camera ray, computed once and shared by every
// method that shades the visible surfaces (and written out by --aov).
#pragma once

#include <cstdint>
#include <vector>

#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/embree/ray_scene.hpp"

namespace penumbra::spaceland {

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

// The median distance from the camera to its first hits (0: none): where it looks.
float focus_distance(const GBuffer& g);

// A G-buffer channel as an image (Aov::radiance is not one).
ImageRgb aov_image(const Scene& scene, const GBuffer& g, Aov aov);

}  // namespace penumbra::spaceland
