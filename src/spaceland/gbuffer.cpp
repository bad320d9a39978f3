#include "spaceland/gbuffer.hpp"

#include <algorithm>
#include <limits>
#include <span>
#include <vector>

#include "core/huge_pages.hpp"
#include "core/parallel.hpp"
#include "spaceland/camera.hpp"
#include "spaceland/color.hpp"
#include "spaceland/sky.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland {

GBuffer make_gbuffer(const Scene& scene, const RayScene& rays) {
  GBuffer g;
  g.width = scene.camera.width;
  g.height = scene.camera.height;
  const std::size_t n = std::size_t(g.width) * g.height;
  // On huge pages: first touching 100 MB of fresh 4 KiB pages (1920x1080) cost more than
  // tracing the camera rays in a virtual machine (core/huge_pages.hpp).
  assign_huge(g.hits, n);
  assign_huge(g.found, n);
  assign_huge(g.directions, n);
  const CameraRays camera(scene.camera);
  g.forward = camera.forward();
  // A row at a time through Embree's stream interface: camera rays through neighbouring pixels
  // are coherent, which it traces about twice as fast as single rays (docs/PERFORMANCE.md).
  parallel_for(g.height, [&](int j) {
    const std::size_t row = std::size_t(j) * g.width;
    thread_local std::vector<Ray> rays_of_row;  // allocated once per thread, not per row
    rays_of_row.resize(std::size_t(g.width));
    for (int i = 0; i < g.width; ++i) {
      rays_of_row[std::size_t(i)] = camera.ray(i, j);
      g.directions[row + std::size_t(i)] = rays_of_row[std::size_t(i)].direction;
    }
    rays.intersect(rays_of_row, std::span<Hit>(g.hits.data() + row, std::size_t(g.width)),
                   std::span<std::uint8_t>(g.found.data() + row, std::size_t(g.width)), true);
    for (int i = 0; i < g.width; ++i)
      if (g.found[row + std::size_t(i)])
        face_towards(g.hits[row + std::size_t(i)], g.directions[row + std::size_t(i)]);
  });
  return g;
}

ImageRgb aov_image(const Scene& scene, const GBuffer& g, Aov aov) {
  ImageRgb img(g.width, g.height);
  const Background bg(scene);
  const float inf = std::numeric_limits<float>::infinity();
  parallel_for(g.height, [&](int j) {
    for (int i = 0; i < g.width; ++i) {
      const std::size_t k = std::size_t(j) * g.width + i;
      const Hit& h = g.hits[k];
      const bool hit = g.found[k] != 0;
      Rgb c{};
      switch (aov) {
        case Aov::depth: {
          const float d = hit ? g.linear_depth(k) : inf;
          c = {d, d, d};
          break;
        }
        case Aov::normal:
          if (hit) c = {h.shading_normal.x, h.shading_normal.y, h.shading_normal.z};
          break;
        case Aov::albedo:
          if (hit) c = albedo_at(scene, h);
          break;
        case Aov::position:
          if (hit) c = {h.position.x, h.position.y, h.position.z};
          break;
        case Aov::emission:
          c = hit ? emission_at(scene, h) : bg(g.directions[k]);
          break;
        case Aov::object: {
          const float o = hit ? float(h.object) : -1.0f;
          c = {o, o, o};
          break;
        }
        case Aov::radiance:
          break;
      }
      img.set(i, j, c);
    }
  });
  return img;
}

float focus_distance(const GBuffer& g) {
  std::vector<float> t;
  t.reserve(g.hits.size());
  for (std::size_t k = 0; k < g.hits.size(); ++k)
    if (g.found[k]) t.push_back(g.hits[k].t);
  if (t.empty()) return 0;
  std::nth_element(t.begin(), t.begin() + std::ptrdiff_t(t.size() / 2), t.end());
  return t[t.size() / 2];
}

}  // namespace penumbra::spaceland
