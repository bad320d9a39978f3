// The probe grid's voxels as nested levels centred on the camera (a clipmap, as the world-space
// grids of seed 001 section 4.3 and its "Radiance 3d" demo): level l has voxels of v0 2^l and
// is kLevelVoxels wide along each axis where the scene is wider, placed around the camera and
// slid to stay within the scene's padded bounds; the last level holds the whole scene. Voxels
// are fine where the camera is and a world of any size fits in a few levels. Each level has its
// own cascades; a ray that leaves a level goes on through the coarser ones (Voxels::outer), and
// a point takes its light from the finest level around it, blended into the next over a band.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/cascade/sphere_lights.hpp"
#include "spaceland/grid/voxels.hpp"

namespace penumbra::spaceland::grid {

// A level's width in voxels along an axis where the scene is wider: 128 and the padding (a
// scene that the default one grid holds, its longest side over 128, is one level).
inline constexpr int kLevelVoxels = 128 + 2 * kPadding;
inline constexpr int kMaxLevels = 8;
// The default finest voxel: the median distance from the camera to what it sees over this (a
// level 0 then reaches about twice that distance each way), or the scene's longest side over 128
// where that is finer.
inline constexpr float kFocusVoxels = 32;

// One level: its part of the padded grid of its voxel size, and which of its faces lie inside
// the scene (cut: the next level goes on past them).
struct ClipLevel {
  float size = 1;
  VoxelBox box;
  Bounds world;                              // the box in world units
  std::array<std::array<bool, 2>, 3> cut{};  // [axis][0: low side, 1: high side]
  // Whether the box [lo, hi] lies within the level's.
  bool contains(Vec3 lo, Vec3 hi) const;
};

// The levels for finest voxel `v0` around `camera`: `levels` of them (the last holding the whole
// scene), or with 0 until one holds it (at most kMaxLevels, the last then holds the whole scene).
std::vector<ClipLevel> clip_levels(const Scene& scene, float v0, int levels, Vec3 camera);
// The voxels of all levels (in double: see VoxelBox::count).
double clipmap_voxels(const std::vector<ClipLevel>& levels);

// The levels a render uses. One grid over the whole scene (as o.levels 1) with extension, or
// by default where `focus` over kFocusVoxels is no finer than the scene's longest side over 128
// (voxel_size's). Otherwise the finest voxel is o.voxel, or `focus` over kFocusVoxels (at least
// the longest side over 128 2^7, where the last of 8 levels holds the scene at their width),
// grown until the levels' voxels fit `max_bytes` (`bounces`: with their second sides).
std::vector<ClipLevel> plan_levels(const Scene& scene, const GridOptions& o,
                                   std::uint64_t max_bytes, bool bounces, float focus);

// The voxels of every level, finest first, each level's `outer` the next. Not copyable (the
// levels point to each other); moving keeps them.
class Clipmap {
 public:
  Clipmap() = default;
  Clipmap(Clipmap&&) noexcept = default;
  Clipmap& operator=(Clipmap&&) noexcept = default;
  Clipmap(const Clipmap&) = delete;
  Clipmap& operator=(const Clipmap&) = delete;

  // Voxelises every level (Error where their voxels pass `max_bytes` together), sphere lights
  // under `within` voxels in radius spread, not voxels (lights()).
  static Expected<Clipmap> build(const Scene& scene, std::vector<ClipLevel> levels,
                                 std::uint64_t max_bytes, float within);

  std::size_t size() const { return levels_.size(); }
  Voxels& operator[](std::size_t l) { return *levels_[l]; }
  const Voxels& operator[](std::size_t l) const { return *levels_[l]; }
  std::uint64_t voxels() const { return std::uint64_t(clipmap_voxels(plan_)); }

  // The sphere lights level l's cascades spread: those under `within` voxels in radius of the level
  // whose voxels its rays meet them in (l, or the finest level holding the light where that is
  // coarser: a ray of l reaches a light outside l's box through that level's voxels).
  cascade::SphereLights lights(const Scene& scene, std::size_t l) const;
  // Every level's, finest first.
  std::vector<cascade::SphereLights> lights(const Scene& scene) const;
  // Every level's own emission (before bounces add to it), finest first.
  std::vector<std::vector<Rgb>> emission() const;

  // How much level l serves point p: 1 inside, down to 0 over `band` voxels towards its cut
  // faces, `margin` voxels before them (the last level serves everywhere).
  float weight(std::size_t l, Vec3 p, float margin, float band) const;

  // The blend of levels at p: `value(l, out)` gives level l's (false: none there, its share goes
  // to the next); false where no level gives one.
  template <class Value>
  bool blend(Vec3 p, float margin, float band, Value&& value, Rgb& out) const {
    Rgb sum{};
    float left = 1, taken = 0;
    for (std::size_t l = 0; l < levels_.size() && left > 0; ++l) {
      const float w = weight(l, p, margin, band);
      if (w <= 0) continue;
      Rgb v;
      if (!value(l, v)) continue;
      sum += v * (left * w);
      taken += left * w;
      left *= 1 - w;
    }
    if (!(taken > 0)) return false;
    out = sum * (1 / taken);
    return true;
  }

 private:
  std::vector<ClipLevel> plan_;
  float within_ = cascade::kSpreadVoxels;
  // Each level on the heap: the levels point to their outer ones.
  std::vector<std::unique_ptr<Voxels>> levels_;
};

}  // namespace penumbra::spaceland::grid
