// Exact ray queries against a Scene, through Embree 3. Embree's types stay in ray_scene.cpp.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "penumbra/error.hpp"
#include "penumbra/spaceland/scene.hpp"

namespace penumbra::spaceland {

struct Ray {
  Vec3 origin;
  Vec3 direction;  // need not be unit; t is in units of its length
  float tmin = 0;
  float tmax = 3.0e38f;
};

// What a closest-hit query found.
enum class ShapeKind : std::uint8_t { triangle, sphere, disk };

struct Hit {
  float t = 0;
  Vec3 position;          // on the surface (origin + t direction, refined for analytic shapes)
  Vec3 geometric_normal;  // unit, as the surface is oriented (not yet turned to the ray)
  Vec3 shading_normal;    // unit: interpolated vertex normal where the mesh has them
  float u = 0, v = 0;     // texture coordinates (0 where the mesh has none)
  std::uint32_t material = 0;
  int object = -1;
  ShapeKind kind = ShapeKind::triangle;
  std::uint32_t shape = 0;      // mesh, sphere or disk index in the Scene
  std::uint32_t primitive = 0;  // triangle index within the mesh
};

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

  // Where to start a ray leaving a surface at `p` with geometric normal `n` towards `direction`:
  // p moved off the surface, to the side `direction` goes, by a distance scaled to the scene's
  // size and p's magnitude (not a fixed epsilon).
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
