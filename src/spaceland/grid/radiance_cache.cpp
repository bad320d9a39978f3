// The radiance cache (spaceland/radiance_cache.hpp) as the probe grid builds it: per surface
// voxel, the light its surfaces reflect after the bounces asked for.
#include "spaceland/radiance_cache.hpp"

#include <algorithm>
#include <vector>

#include "spaceland/grid/grid.hpp"
#include "spaceland/sun.hpp"

namespace penumbra::spaceland {

struct RadianceCache::Impl {
  grid::Voxels voxels;               // where the surfaces are (the extinction's opaque mark)
  std::vector<Rgb> reflected;        // towards the + side of a thin wall's axis, or any side
  std::vector<Rgb> reflected_minus;  // thin walls: towards the - side
  std::vector<Vec3> normals;         // thin walls: the + side's
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
                                             int bounces) {
  if (bounces < 1) return Error{"the radiance cache holds at least one bounce"};
  Expected<grid::Voxels> voxels =
      grid::voxelise(scene, grid::voxel_size(scene, o, max_memory), max_memory / 4);
  if (!voxels) return voxels.error();
  const Background bg(scene);
  const std::uint64_t left =
      max_memory - std::min(max_memory, grid::voxel_bytes(voxels->count(), true));
  auto impl = std::make_unique<Impl>();
  impl->voxels = std::move(*voxels);
  grid::Voxels& v = impl->voxels;
  const std::vector<Rgb> base = v.emission;
  const SunLight sun(scene, rays);
  const cascade::SphereLights lights(scene, v.size);
  for (int b = 0; b < bounces; ++b) {
    Expected<grid::RadianceField> field = grid::solve(v, bg, o, left, &lights);
    if (!field) return field.error();
    grid::add_bounce(v, *field, base, &sun, &impl->normals);
  }
  impl->reflected.resize(base.size());
  impl->reflected_minus.resize(base.size());
  for (std::size_t k = 0; k < base.size(); ++k) {
    impl->reflected[k] = v.emission[k] - base[k];
    impl->reflected_minus[k] = v.emission_minus[k] - base[k];
  }
  // Lookups need only where the surfaces are (the extinction's opaque mark) and the thin walls.
  std::vector<Rgb>().swap(v.emission);
  std::vector<Rgb>().swap(v.emission_minus);
  std::vector<Rgb>().swap(v.albedo);
  std::vector<std::uint8_t>().swap(v.skip);
  return RadianceCache(std::move(impl));
}

Rgb RadianceCache::reflected(Vec3 p, Vec3 n) const {
  const grid::Voxels& v = impl_->voxels;
  int at[3];
  const int dims[3] = {v.nx, v.ny, v.nz};
  for (int k = 0; k < 3; ++k) at[k] = v.cell(p, k);
  float best = cascade::kInfinity;
  Rgb out{};
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
        Vec3 normal = impl_->normals[k];
        bool minus = false;
        if (v.thin[k]) {
          const int axis = v.thin[k] - 1;
          minus = n[axis] < 0;
          if (minus) normal[axis] = -normal[axis];
        }
        if (!(dot(normal, n) > 0.5f)) continue;
        const float d = float(dx * dx + dy * dy + dz * dz);
        if (d < best) best = d, out = minus ? impl_->reflected_minus[k] : impl_->reflected[k];
      }
  return out;
}

// The opacity marks (the voxels' extinction), the reflected light (two sides), the normals and
// the thin walls' marks.
std::uint64_t RadianceCache::bytes() const {
  return impl_->reflected.size() * (sizeof(Rgb) * 3 + sizeof(Vec3) + sizeof(std::uint8_t));
}

}  // namespace penumbra::spaceland
