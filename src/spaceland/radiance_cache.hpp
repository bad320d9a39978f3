// A world-space radiance cache: the light the scene's surfaces reflect after some bounces, which
// any method that does not follow bounces itself reads at the surfaces its rays meet (seed 001
// section 4.3's probe grid used as a cache). Built from the world-space probe grid (grid/), but
// its users see only this.
#pragma once

#include <cstdint>
#include <memory>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/embree/ray_scene.hpp"

namespace penumbra::spaceland {

class RadianceCache {
 public:
  // Voxelises the scene (the probe grid's levels around the camera, `focus` the median distance
  // to what it sees: grid::plan_levels) and solves the probe grid (`grid`'s options, a quarter
  // of `max_memory` for the voxels) `bounces` times; `rays` carry the sun to the voxels.
  static Expected<RadianceCache> build(const Scene& scene, const RayScene& rays,
                                       const GridOptions& grid, std::uint64_t max_memory,
                                       int bounces, float focus);
  // The grid options' ranges (any scene will do), checked before a scene is read.
  static Status check_options(const GridOptions& grid);
  // Its memory need (the voxels), known before anything is allocated.
  static std::uint64_t estimate_bytes(const Scene& scene, const GridOptions& grid,
                                      std::uint64_t max_memory);

  RadianceCache(RadianceCache&&) noexcept;
  RadianceCache& operator=(RadianceCache&&) noexcept;
  ~RadianceCache();

  // The reflected radiance at surface point p towards the side of unit normal n: the nearest
  // surface voxel around p (of the finest level around it, blended into the next by its cut
  // faces) whose own normal faces n's way (a surface on a voxel face marks the
  // voxels on both sides, and near an edge the other surface's too; a wall one voxel thick holds
  // both sides); 0 where there is none.
  Rgb reflected(Vec3 p, Vec3 n) const;
  std::uint64_t bytes() const;
  // The finest level's voxel size and the levels (the grid options it ran with).
  float voxel() const;
  int levels() const;

  struct Impl;

 private:
  explicit RadianceCache(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace penumbra::spaceland
