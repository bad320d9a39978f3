// The probe grid's nested levels: where each lies, their voxels, and how a point reads them.
#include "spaceland/grid/clipmap.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

namespace penumbra::spaceland::grid {

namespace {

// The padded grid's lowest corner for voxels of `size` (voxel (0, 0, 0) of the whole grid).
Vec3 grid_origin(const Bounds& b, float size) {
  return b.lo - Vec3{size, size, size} * float(kPadding);
}

// One level of voxels `size` around `camera`: kLevelVoxels wide along an axis where the whole
// grid is wider, slid to lie within it (`whole`: the whole grid).
ClipLevel place(const Bounds& b, float size, Vec3 camera, bool whole) {
  ClipLevel level;
  level.size = size;
  const std::array<double, 3> full = grid_dims(b, size);
  const Vec3 origin = grid_origin(b, size);
  for (int k = 0; k < 3; ++k) {
    // (a voxel too small for the counts is the voxelising's to refuse)
    const int n = int(std::min(full[std::size_t(k)], double(1 << 30)));
    auto& first = level.box.first[std::size_t(k)];
    auto& dims = level.box.dims[std::size_t(k)];
    if (whole || n <= kLevelVoxels) {
      first = 0, dims = n;
      continue;
    }
    const double at = std::floor((double(camera[k]) - origin[k]) / size);
    first = int(std::clamp(at - kLevelVoxels / 2, 0.0, double(n - kLevelVoxels)));
    dims = kLevelVoxels;
    level.cut[std::size_t(k)] = {first > 0, first + kLevelVoxels < n};
  }
  for (int k = 0; k < 3; ++k) {
    level.world.lo[k] = origin[k] + float(level.box.first[std::size_t(k)]) * size;
    level.world.hi[k] = level.world.lo[k] + float(level.box.dims[std::size_t(k)]) * size;
  }
  return level;
}

bool any_cut(const ClipLevel& l) {
  for (const auto& axis : l.cut)
    if (axis[0] || axis[1]) return true;
  return false;
}

// Whether level l's cascades spread sphere s: under `within` voxels in radius of the level whose
// voxels l's rays meet it in (l, or the finest level holding it where that is coarser).
bool spread_at(const Scene& scene, const std::vector<ClipLevel>& levels, std::size_t l,
               const Sphere& s, float within) {
  const Vec3 r{s.radius, s.radius, s.radius};
  std::size_t home = levels.size() - 1;
  for (std::size_t j = 0; j < levels.size(); ++j)
    if (levels[j].contains(s.center - r, s.center + r)) {
      home = j;
      break;
    }
  return cascade::spread_by_grid(scene, s, levels[std::max(l, home)].size, within);
}

}  // namespace

bool ClipLevel::contains(Vec3 lo, Vec3 hi) const {
  for (int k = 0; k < 3; ++k)
    if (lo[k] < world.lo[k] || hi[k] > world.hi[k]) return false;
  return true;
}

std::vector<ClipLevel> clip_levels(const Scene& scene, float v0, int levels, Vec3 camera) {
  const Bounds b = grid_bounds(scene);
  std::vector<ClipLevel> out;
  const int most = levels > 0 ? levels : kMaxLevels;
  for (int l = 0; l < most; ++l) {
    out.push_back(place(b, v0 * float(1 << l), camera, l + 1 == most));
    if (!any_cut(out.back())) break;
  }
  return out;
}

double clipmap_voxels(const std::vector<ClipLevel>& levels) {
  double n = 0;
  for (const ClipLevel& l : levels) n += l.box.count();
  return n;
}

std::vector<ClipLevel> plan_levels(const Scene& scene, const GridOptions& o,
                                   std::uint64_t max_bytes, bool bounces, float focus) {
  const Vec3 camera = scene.camera.position;
  const Bounds b = grid_bounds(scene);
  const double longest =
      std::max({double(b.hi.x) - b.lo.x, double(b.hi.y) - b.lo.y, double(b.hi.z) - b.lo.z, 1e-6});
  // One grid over the whole scene: asked for, with extension (its shifted intervals read the
  // cascade's own probes, which a level does not have past its cut faces), or where the camera's
  // focus asks for no finer voxel than the scene's longest side over 128 (the same grid as
  // --levels 1, bit for bit).
  const bool one = o.levels == 1 || o.extend_length > 0;
  if (one || (o.voxel == 0 && o.levels == 0 && !(focus / kFocusVoxels < longest / 128))) {
    const float size = o.voxel > 0 ? o.voxel : default_voxel_size(scene, max_bytes);
    return {place(b, size, camera, true)};
  }
  if (o.voxel > 0) return clip_levels(scene, o.voxel, o.levels, camera);
  // No finer than the last level holding the scene at its width (longest / 128 / 2^7).
  double v0 = std::min(longest / 128, std::max(double(focus) / kFocusVoxels,
                                               longest / 128 / (1 << (kMaxLevels - 1))));
  std::vector<ClipLevel> levels = clip_levels(scene, float(v0), o.levels, camera);
  // Coarser until the voxels fit (past the scene's size they can shrink no more: voxelising
  // refuses then).
  while (double(voxel_bytes(1, bounces)) * clipmap_voxels(levels) > double(max_bytes) &&
         v0 < 4 * longest) {
    v0 *= 1.25;
    levels = clip_levels(scene, float(v0), o.levels, camera);
  }
  return levels;
}

Expected<Clipmap> Clipmap::build(const Scene& scene, std::vector<ClipLevel> levels,
                                 std::uint64_t max_bytes, float within) {
  const double need = double(voxel_bytes(1)) * clipmap_voxels(levels);
  Clipmap map;
  for (const ClipLevel& l : levels) {
    // Each level checked against what the others leave (their sum against the limit).
    const double others = need - double(voxel_bytes(1)) * l.box.count();
    // The sphere lights this level's cascades spread are not its voxels (one that a cut face
    // crosses, spread by the level that holds it, is not half voxels here).
    std::vector<std::uint8_t> left_out(scene.spheres.size());
    for (std::size_t i = 0; i < left_out.size(); ++i)
      left_out[i] = spread_at(scene, levels, map.levels_.size(), scene.spheres[i], within);
    Expected<Voxels> v = voxelise(
        scene, l.size, std::uint64_t(std::max(0.0, double(max_bytes) - others)), &l.box, &left_out);
    if (!v) return v.error();
    map.levels_.push_back(std::make_unique<Voxels>(std::move(*v)));
  }
  for (std::size_t l = 0; l + 1 < map.levels_.size(); ++l)
    map.levels_[l]->outer = map.levels_[l + 1].get();
  map.plan_ = std::move(levels);
  map.within_ = within;
  return map;
}

cascade::SphereLights Clipmap::lights(const Scene& scene, std::size_t l) const {
  return cascade::SphereLights::spread_by(
      scene, [&](const Sphere& s) { return spread_at(scene, plan_, l, s, within_); });
}

std::vector<cascade::SphereLights> Clipmap::lights(const Scene& scene) const {
  std::vector<cascade::SphereLights> out;
  for (std::size_t l = 0; l < size(); ++l) out.push_back(lights(scene, l));
  return out;
}

std::vector<std::vector<Rgb>> Clipmap::emission() const {
  std::vector<std::vector<Rgb>> out;
  for (const std::unique_ptr<Voxels>& v : levels_) out.push_back(v->emission);
  return out;
}

float Clipmap::weight(std::size_t l, Vec3 p, float margin, float band) const {
  if (l + 1 == levels_.size()) return 1;
  const Voxels& v = *levels_[l];
  const int dims[3] = {v.nx, v.ny, v.nz};
  float w = 1;
  for (int k = 0; k < 3; ++k) {
    const float in = (p[k] - v.origin[k]) / v.size;  // voxels from the low face
    const float sides[2] = {in, float(dims[k]) - in};
    for (int side = 0; side < 2; ++side)
      if (plan_[l].cut[std::size_t(k)][std::size_t(side)])
        w = std::min(w, std::clamp((sides[side] - margin) / band, 0.0f, 1.0f));
  }
  return w;
}

}  // namespace penumbra::spaceland::grid
