#include "spaceland/surface.hpp"

#include <cstdint>
#include <string>
#include <vector>

#include "spaceland/color.hpp"
#include "spaceland/scene/mesh_file.hpp"

namespace penumbra::spaceland {

namespace {

// The texel of `ref` at the hit: its set of texture coordinates, through its transform.
Rgb texel_at(const Scene& scene, const Hit& hit, const TextureRef& ref) {
  float u = hit.u, v = hit.v;
  if (ref.uv_set == 1) {
    u = v = 0;
    if (hit.kind == ShapeKind::triangle) {
      const TriangleMesh& m = scene.meshes[hit.shape];
      if (!m.lightmap_uvs.empty()) {
        const auto& tri = m.triangles[hit.primitive];
        const float b0 = 1 - hit.b1 - hit.b2;
        const auto &t0 = m.lightmap_uvs[tri[0]], &t1 = m.lightmap_uvs[tri[1]],
                   &t2 = m.lightmap_uvs[tri[2]];
        u = b0 * t0[0] + hit.b1 * t1[0] + hit.b2 * t2[0];
        v = b0 * t0[1] + hit.b1 * t1[1] + hit.b2 * t2[1];
      }
    }
  }
  const auto& t = ref.transform;
  return sample_texture(scene.textures[std::size_t(ref.index)], t[0] * u + t[1] * v + t[2],
                        t[3] * u + t[4] * v + t[5]);
}

}  // namespace

Rgb albedo_at(const Scene& scene, const Hit& hit) {
  const Material& m = scene.materials[hit.material];
  if (m.albedo_texture.index < 0) return m.albedo;
  return m.albedo * texel_at(scene, hit, m.albedo_texture);
}

Rgb emission_at(const Scene& scene, const Hit& hit) {
  const Material& m = scene.materials[hit.material];
  if (m.emission_texture.index < 0) return m.emission;
  return m.emission * texel_at(scene, hit, m.emission_texture);
}

Brdf brdf_at(const Scene& scene, const Hit& hit) {
  const Material& m = scene.materials[hit.material];
  const Rgb albedo = albedo_at(scene, hit);
  if (m.metallic_roughness_texture.index < 0) return make_brdf(albedo, m.metallic, m.roughness);
  const Rgb mr = texel_at(scene, hit, m.metallic_roughness_texture);
  return make_brdf(albedo, m.metallic * mr.b, m.roughness * mr.g);
}

std::vector<char> materials_in_use(const Scene& scene) {
  std::vector<char> used(scene.materials.size(), 0);
  auto use = [&](std::uint32_t m) {
    if (m < used.size()) used[m] = 1;
  };
  for (const TriangleMesh& mesh : scene.meshes)
    for (std::uint32_t m : mesh.materials) use(m);
  for (const Sphere& sp : scene.spheres) use(sp.material);
  for (const Disk& d : scene.disks) use(d.material);
  return used;
}

void face_towards(Hit& hit, Vec3 d) {
  if (dot(hit.geometric_normal, d) > 0) hit.geometric_normal = -hit.geometric_normal;
  if (dot(hit.shading_normal, d) > 0) hit.shading_normal = -hit.shading_normal;
}

}  // namespace penumbra::spaceland
