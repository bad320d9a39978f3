// The scene as a voxel grid (seed 001 sections 2.5.2 and 4.3): what the world-space probe grid
// traces. Surfaces are rasterised conservatively (every voxel a surface touches is opaque, so a
// ray cannot cross a wall one voxel thick), fog boxes become partial extinction (the fraction of
// the voxel they cover), and a ray picks up light voxel by voxel with the same transport as the
// 2D cells: Beer-Lambert with a source, opaque voxels ending it.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/cascade/radiance.hpp"
#include "spaceland/color.hpp"

namespace penumbra::spaceland::grid {

inline constexpr float kOpaque = std::numeric_limits<float>::infinity();
// Free voxels around the scene's bounds on every side: room for probes in front of the outermost
// surfaces (a floor's probes sit above it, the conservative rasterisation takes a voxel).
inline constexpr int kPadding = 4;

struct Voxels {
  Vec3 origin;     // the lowest corner of voxel (0, 0, 0)
  float size = 1;  // edge length, world units
  int nx = 0, ny = 0, nz = 0;
  // Per voxel, x fastest, then y, then z:
  std::vector<Rgb> extinction;  // per world unit; kOpaque (every channel) where a surface is
  std::vector<Rgb> emission;    // surfaces: emitted radiance; fog: radiance emitted per unit length
  std::vector<Rgb> albedo;      // surfaces: their mean albedo; fog: single-scattering albedo
  // Once bounces give the surfaces their reflected light (add_bounce), a surface voxel free on
  // both sides of an axis (a wall one voxel thick) holds one value per side: `thin` is 1 + that
  // axis (0 elsewhere), `emission` the light it sends towards the axis's + side and
  // `emission_minus` towards its - side. Empty before the first bounce.
  std::vector<std::uint8_t> thin;
  std::vector<Rgb> emission_minus;
  // Empty-space skipping: per voxel, the chessboard distance (in voxels, at most 255) to the
  // nearest voxel that is not empty (opaque, fog, or emitting); 0 on those. A march in a voxel at
  // distance d >= 2 jumps to the exit of the empty cube of d - 1 voxels around it. Empty: no
  // skipping (the same answer, a voxel at a time).
  std::vector<std::uint8_t> skip;
  // In a clipmap (clipmap.hpp), the next coarser level: a ray that leaves this grid goes on
  // through it (null: out of the grid there is nothing).
  const Voxels* outer = nullptr;

  std::size_t index(int x, int y, int z) const {
    return (std::size_t(z) * std::size_t(ny) + std::size_t(y)) * std::size_t(nx) + std::size_t(x);
  }
  std::uint64_t count() const { return std::uint64_t(nx) * std::uint64_t(ny) * std::uint64_t(nz); }
  bool opaque(std::size_t k) const { return extinction[k].r == kOpaque; }
  // What surface voxel k sends back along a ray travelling along `dir`.
  const Rgb& emission_towards(std::size_t k, Vec3 dir) const {
    if (thin.empty() || thin[k] == 0) return emission[k];
    return dir[thin[k] - 1] > 0 ? emission_minus[k] : emission[k];
  }
  // The voxel index along `axis` of point p (outside [0, n) beyond the grid).
  int cell(Vec3 p, int axis) const { return int(std::floor((p[axis] - origin[axis]) / size)); }
  Vec3 centre(int x, int y, int z) const {
    return origin +
           Vec3{(float(x) + 0.5f) * size, (float(y) + 0.5f) * size, (float(z) + 0.5f) * size};
  }
};

// Bytes a grid of n voxels holds (the distance field included); `sides`: at its peak through
// bounces (the thin walls' second values, the surfaces' own emission kept aside, add_bounce's
// new arrays beside the old).
std::uint64_t voxel_bytes(std::uint64_t n, bool sides = false);

// What voxelise covers: the surfaces' and the fog boxes' bounds.
Bounds grid_bounds(const Scene& scene);

// Voxels along each axis of a grid of voxels of `size` over `b`, the padding included (as
// doubles: a size too small for the counts to fit is the caller's to refuse).
std::array<double, 3> grid_dims(const Bounds& b, double size);

// The default voxel size: the bounds' longest side over 128, larger where such a grid would take
// more than `max_bytes`.
float default_voxel_size(const Scene& scene, std::uint64_t max_bytes);

// A part of the padded grid over grid_bounds, in its voxels: `dims` voxels from voxel `first`
// (the whole grid: first 0, dims grid_dims).
struct VoxelBox {
  std::array<int, 3> first{}, dims{};
  // In double: a box asked of a voxel far too small for it must be refused, not wrap.
  double count() const { return double(dims[0]) * double(dims[1]) * double(dims[2]); }
};

// Voxelises the scene with voxels of `size` (world units) over grid_bounds, padded by kPadding,
// or over `box`, a part of that grid. A surface voxel takes the area-weighted mean emission and
// albedo (times its texture's mean) of the surfaces in it; a fog voxel the coefficients of the
// boxes covering it, times the fraction they cover (4^3 points a voxel; overlapping boxes add).
// Sphere lights the cascades spread are left out: `left_out`, per scene sphere, where given,
// else those under cascade::kSpreadVoxels voxels in radius (cascade::spread_by_grid). Refuses
// (Error, nothing allocated) a size that is not a positive number or a grid over `max_bytes`.
Expected<Voxels> voxelise(const Scene& scene, float size, std::uint64_t max_bytes,
                          const VoxelBox* box = nullptr,
                          const std::vector<std::uint8_t>* left_out = nullptr);

// The light a homogeneous stretch (extinction `sigma`, a source of `source` radiance per unit
// length) of length `len` sends to its start, seen through its own extinction; `pass` is its
// transmittance exp(-sigma len), which the caller has (the fog on a camera ray reuses it).
inline Rgb stretch_light(Rgb sigma, Rgb source, float len, Rgb pass) {
  Rgb out;
  for (int c = 0; c < 3; ++c) {
    const float s = channel(sigma, c), e = channel(source, c), tau = s * len;
    const float v = tau > 1e-4f ? e * (1 - channel(pass, c)) / s
                                : e * len * (1 - 0.5f * tau);  // the same, without 0/0
    (c == 0 ? out.r : c == 1 ? out.g : out.b) = v;
  }
  return out;
}

// What a ray segment picks up crossing the grid (the cascade core's: blocked by an opaque voxel,
// t_end its entry).
using cascade::Segment;

// Walks the voxels along origin + t dir (dir unit), t in [tmin, tmax], one voxel at a time
// (Amanatides-Woo), leaping over empty space by the distance field: in a fog voxel, Beer-Lambert
// with its emission as the source; an opaque voxel adds its emission (seen through what came
// before) and ends the segment. Past the grid's box the ray goes on through v.outer, if any
// (else there is nothing).
Segment march(const Voxels& v, Vec3 origin, Vec3 dir, float tmin, float tmax);

// Fills v.skip from the voxels' contents (voxelise does; bounces change no empty voxel).
void build_distance_field(Voxels& v);

}  // namespace penumbra::spaceland::grid
