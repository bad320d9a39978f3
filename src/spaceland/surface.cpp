#include "spaceland/surface.hpp"

#include "spaceland/color.hpp"
#include "spaceland/scene/mesh_file.hpp"

namespace penumbra::spaceland {

Rgb albedo_at(const Scene& scene, const Hit& hit) {
  const Material& m = scene.materials[hit.material];
  if (m.albedo_texture < 0) return m.albedo;
  return m.albedo * sample_texture(scene.textures[std::size_t(m.albedo_texture)], hit.u, hit.v);
}

Rgb emission_at(const Scene& scene, const Hit& hit) {
  return scene.materials[hit.material].emission;
}

void face_towards(Hit& hit, Vec3 d) {
  if (dot(hit.geometric_normal, d) > 0) hit.geometric_normal = -hit.geometric_normal;
  if (dot(hit.shading_normal, d) > 0) hit.shading_normal = -hit.shading_normal;
}

}  // namespace penumbra::spaceland
