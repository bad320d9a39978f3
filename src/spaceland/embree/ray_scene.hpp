// Exact ray queries against a Scene, through Embree 3. Embree's types stay in ray_scene.cpp.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "penumbra/error.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/ray.hpp"

namespace penumbra::spaceland {

// One Embree scene per Scene: a triangle geometry per mesh, the spheres and the disks as exact
// point geometries. Queries are thread-safe.
class RayScene {
 public:
  // Builds the BVH (the scene must pass check_scene). Errors: Embree failures (out of memory).
  static Expected<RayScene> build(const Scene& scene);
  // The same, refusing (with an Error) to let Embree allocate more than `max_bytes`.
  static Expected<RayScene> build(const Scene& scene, std::uint64_t max_bytes);
  // Bytes the BVH and Embree's copies of the geometry are expected to take.
  static std::uint64_t estimate_bytes(const Scene& scene);

  RayScene(RayScene&&) noexcept;
  RayScene& operator=(RayScene&&) noexcept;
  ~RayScene();

  // Closest hit in (tmin, tmax); false on a miss.
  bool intersect(const Ray& ray, Hit& hit) const;
  // Any hit in (tmin, tmax): a shadow ray.
  bool occluded(const Ray& ray) const;
  // Many rays at once: hits[i] is filled where found[i] is 1. `coherent` (rays from one point
  // through neighbouring pixels or direction cells, in order) uses Embree's stream interface,
  // faster for those and slower for scattered rays; the answers are the same either way.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, std::span<std::uint8_t> found,
                 bool coherent = false) const;
  void occluded(std::span<const Ray> rays, std::span<std::uint8_t> blocked) const;

  // Where to start a ray leaving a surface at `p` with geometric normal `n` towards `direction`
  // (spawn_point at this scene's scale).
  Vec3 spawn(Vec3 p, Vec3 n, Vec3 direction) const;
  // A shadow ray from a surface point towards a target point: ends short of the target by the
  // same scaled offset, so the target's own surface does not block it.
  Ray shadow_ray(Vec3 p, Vec3 n, Vec3 target) const;
  // The same towards a target whose surface normal is known (a sampled light point): the ray ends
  // at the target moved off its surface towards p, safe at grazing angles too.
  Ray shadow_ray(Vec3 p, Vec3 n, Vec3 target, Vec3 target_normal) const;
  float epsilon() const;  // the offset scale

  std::uint64_t bytes() const;  // memory the BVH took (Embree's own accounting)

 private:
  struct Impl;
  explicit RayScene(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace penumbra::spaceland
