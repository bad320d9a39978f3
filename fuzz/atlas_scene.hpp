// The scene fuzz_atlas reads atlases for and make_seeds bakes its seed atlases from: a floor
// quad under a sphere light, built in code so that both make the same scene hash.
#pragma once

#include "penumbra/spaceland/scene.hpp"

inline penumbra::spaceland::Scene atlas_fuzz_scene() {
  namespace sl = penumbra::spaceland;
  sl::Scene s;
  s.camera.position = {0, 2, 3};
  s.camera.width = 8;
  s.camera.height = 6;
  s.sky.zenith = s.sky.horizon = s.sky.ground = {0.1f, 0.1f, 0.2f};
  sl::Material floor;
  floor.albedo = {0.5f, 0.5f, 0.5f};
  sl::Material lamp;
  lamp.albedo = {0, 0, 0};
  lamp.emission = {8, 6, 4};
  s.materials = {floor, lamp};
  sl::TriangleMesh quad;
  quad.positions = {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
  quad.triangles = {{0, 2, 1}, {0, 3, 2}};
  quad.materials = {0, 0};
  quad.object = 0;
  s.meshes.push_back(quad);
  sl::Sphere light;
  light.center = {0, 0.8f, 0};
  light.radius = 0.2f;
  light.material = 1;
  light.object = 1;
  s.spheres.push_back(light);
  s.objects = {"floor", "lamp"};
  return s;
}
