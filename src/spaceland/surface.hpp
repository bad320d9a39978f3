// What a surface hit is made of: its albedo and emission from the scene's materials, and its
// normals turned to the side a ray arrives from.
#pragma once

#include <vector>

#include "penumbra/spaceland/scene.hpp"
#include "spaceland/brdf.hpp"
#include "spaceland/ray.hpp"

namespace penumbra::spaceland {

// The albedo (texture included) and the emission of the surface at a hit.
Rgb albedo_at(const Scene& scene, const Hit& hit);
Rgb emission_at(const Scene& scene, const Hit& hit);

// The BRDF at a hit: its base colour, metallic and roughness, textures included.
Brdf brdf_at(const Scene& scene, const Hit& hit);

// A sphere whose material emits: a sphere light, which the cascades spread over their direction
// cells instead of tracing (cascade/sphere_lights.hpp).
inline bool is_sphere_light(const Scene& scene, const Sphere& s) {
  const Rgb& e = scene.materials[s.material].emission;
  return e.r > 0 || e.g > 0 || e.b > 0;
}

// Per material of the scene, 1 where a surface (a mesh's triangle, a sphere, a disk) uses it:
// a file's library may name materials nothing uses (an MTL file, glTF's defaults).
std::vector<char> materials_in_use(const Scene& scene);

// Turns a hit's normals to the side the ray arrives from (surfaces are two-sided).
void face_towards(Hit& hit, Vec3 ray_direction);

}  // namespace penumbra::spaceland
