// The radiance cache (spaceland/radiance_cache.hpp) as the probe grid builds it: per surface
// voxel, the light its surfaces reflect after the bounces asked for.
#include "spaceland/radiance_cache.hpp"

#include <algorithm>
#include <vector>

#include "spaceland/grid/grid.hpp"
#include "spaceland/sun.hpp"

namespace penumbra::spaceland {

// One level's lookups.
struct CacheLevel {
  std::vector<Rgb> reflected;        // towards the + side of a thin wall's axis, or any side
  std::vector<Rgb> reflected_minus;  // thin walls: towards the - side
  std::vector<Vec3> normals;         // thin walls: the + side's
};

struct RadianceCache::Impl {
  grid::Clipmap voxels;  // where the surfaces are (the extinction's opaque mark), per level
  std::vector<CacheLevel> levels;
  Rgb reflected(std::size_t l, Vec3 p, Vec3 n, bool& found) const;
};

RadianceCache::RadianceCache(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RadianceCache::RadianceCache(RadianceCache&&) noexcept = default;
RadianceCache& RadianceCache::operator=(RadianceCache&&) noexcept = default;
RadianceCache::~RadianceCache() = default;

Status RadianceCache::check_options(const GridOptions& grid) {
  return grid::check_options(grid);
}

std::uint64_t RadianceCache::estimate_bytes(const Scene& scene, const GridOptions& grid,
                                            std::uint64_t max_memory) {
  return grid::estimate_bytes(scene, grid, max_memory, true);
}

Expected<RadianceCache> RadianceCache::build(const Scene& scene, const RayScene& rays,
                                             const GridOptions& o, std::uint64_t max_memory,
                                             int bounces, float focus) {
  if (bounces < 1) return Error{"the radiance cache holds at least one bounce"};
  Expected<grid::Clipmap> map =
      grid::Clipmap::build(scene, grid::plan_levels(scene, o, max_memory / 4, true, focus),
                           max_memory / 4, grid::spread_voxels(o));
  if (!map) return map.error();
  const Background bg(scene);
  const std::uint64_t left =
      max_memory - std::min(max_memory, grid::voxel_bytes(map->voxels(), true));
  auto impl = std::make_unique<Impl>();
  impl->voxels = std::move(*map);
  grid::Clipmap& levels = impl->voxels;
  impl->levels.resize(levels.size());
  const std::vector<std::vector<Rgb>> base = levels.emission();
  const std::vector<cascade::SphereLights> lights = levels.lights(scene);
  const SunLight sun(scene, rays);
  std::vector<std::vector<Vec3>> normals(levels.size());
  for (int b = 0; b < bounces; ++b) {
    Expected<grid::LevelFields> fields = grid::solve_levels(levels, bg, o, left, lights);
    if (!fields) return fields.error();
    grid::add_bounces(levels, *fields, base, &sun, &normals);
  }
  for (std::size_t l = 0; l < levels.size(); ++l) impl->levels[l].normals = std::move(normals[l]);
  for (std::size_t l = 0; l < levels.size(); ++l) {
    grid::Voxels& v = levels[l];
    CacheLevel& c = impl->levels[l];
    c.reflected.resize(base[l].size());
    c.reflected_minus.resize(base[l].size());
    for (std::size_t k = 0; k < base[l].size(); ++k) {
      c.reflected[k] = v.emission[k] - base[l][k];
      c.reflected_minus[k] = v.emission_minus[k] - base[l][k];
    }
    // Lookups need only where the surfaces are (the extinction's opaque mark) and the thin walls.
    std::vector<Rgb>().swap(v.emission);
    std::vector<Rgb>().swap(v.emission_minus);
    std::vector<Rgb>().swap(v.albedo);
    std::vector<std::uint8_t>().swap(v.skip);
  }
  return RadianceCache(std::move(impl));
}

Rgb RadianceCache::Impl::reflected(std::size_t l, Vec3 p, Vec3 n, bool& found) const {
  const grid::Voxels& v = voxels[l];
  const CacheLevel& c = levels[l];
  int at[3];
  const int dims[3] = {v.nx, v.ny, v.nz};
  for (int k = 0; k < 3; ++k) at[k] = v.cell(p, k);
  float best = cascade::kInfinity;
  Rgb out{};
  found = false;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int q[3] = {at[0] + dx, at[1] + dy, at[2] + dz};
        if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= dims[0] || q[1] >= dims[1] ||
            q[2] >= dims[2])
          continue;
        const std::size_t k = v.index(q[0], q[1], q[2]);
        if (!v.opaque(k)) continue;
        // A wall one voxel thick: the side n lies on, its normal mirrored for the - side.
        Vec3 normal = c.normals[k];
        bool minus = false;
        if (v.thin[k]) {
          const int axis = v.thin[k] - 1;
          minus = n[axis] < 0;
          if (minus) normal[axis] = -normal[axis];
        }
        if (!(dot(normal, n) > 0.5f)) continue;
        const float d = float(dx * dx + dy * dy + dz * dz);
        if (d < best) best = d, out = minus ? c.reflected_minus[k] : c.reflected[k], found = true;
      }
  return out;
}

Rgb RadianceCache::reflected(Vec3 p, Vec3 n) const {
  // The finest level around p, blended into the next over 4 voxels from a voxel inside its cut
  // faces (the lookup reads the voxels next to p's).
  Rgb out{};
  impl_->voxels.blend(
      p, 1, 4,
      [&](std::size_t l, Rgb& v) {
        bool found;
        v = impl_->reflected(l, p, n, found);
        return found;
      },
      out);
  return out;
}

// The opacity marks (the voxels' extinction), the reflected light (two sides), the normals and
// the thin walls' marks.
std::uint64_t RadianceCache::bytes() const {
  std::uint64_t n = 0;
  for (const CacheLevel& c : impl_->levels)
    n += c.reflected.size() * (sizeof(Rgb) * 3 + sizeof(Vec3) + sizeof(std::uint8_t));
  return n;
}

float RadianceCache::voxel() const {
  return impl_->voxels[0].size;
}

int RadianceCache::levels() const {
  return int(impl_->voxels.size());
}

}  // namespace penumbra::spaceland
