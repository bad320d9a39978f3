// The probe grid's layout: where a cascade's probes sit among the voxels, which are free, and
// which 8 probes of a cascade surround a world point, with their trilinear weights.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "spaceland/cascade/radiance.hpp"
#include "spaceland/grid/grid.hpp"
#include "spaceland/grid/voxels.hpp"

namespace penumbra::spaceland::grid {

// The voxel a probe of spacing s sits in, along one axis: the middle of its block.
inline int probe_voxel(int a, int s) {
  return a * s + s / 2;
}

// p's continuous probe coordinate along `axis` in a cascade of that spacing (probe a at a).
inline double probe_coordinate(const Voxels& v, int spacing, Vec3 p, int axis) {
  return ((double(p[axis]) - v.origin[axis]) / v.size - 0.5 - spacing / 2) / spacing;
}

// The 8 probes of cascade c around world point p and their trilinear weights (corners outside
// the grid clamped onto it).
inline cascade::Corners corners(const Voxels& v, const CascadePlan& c, Vec3 p) {
  int lo[3];
  float f[3];
  const int n[3] = {c.nx, c.ny, c.nz};
  for (int k = 0; k < 3; ++k) {
    const double g = probe_coordinate(v, c.spacing, p, k);
    const double a = std::floor(g);
    lo[k] = int(a);
    f[k] = float(g - a);
    if (lo[k] < 0) lo[k] = 0, f[k] = 0;
    if (lo[k] >= n[k] - 1) lo[k] = std::max(0, n[k] - 1), f[k] = 0;
  }
  cascade::Corners out;
  out.n = 8;
  for (int j = 0; j < 8; ++j) {
    const int x = std::min(lo[0] + (j & 1), c.nx - 1),
              y = std::min(lo[1] + ((j >> 1) & 1), c.ny - 1),
              z = std::min(lo[2] + ((j >> 2) & 1), c.nz - 1);
    out.index[std::size_t(j)] = (std::uint64_t(z) * c.ny + y) * c.nx + x;
    out.w[std::size_t(j)] = ((j & 1) ? f[0] : 1 - f[0]) * (((j >> 1) & 1) ? f[1] : 1 - f[1]) *
                            (((j >> 2) & 1) ? f[2] : 1 - f[2]);
  }
  return out;
}

// The voxel probe q of cascade c sits in (past the grid's end where the counts round up).
inline std::array<int, 3> probe_cell(const CascadePlan& c, std::uint64_t q) {
  const int x = int(q % std::uint64_t(c.nx)),
            y = int(q / std::uint64_t(c.nx) % std::uint64_t(c.ny)),
            z = int(q / (std::uint64_t(c.nx) * c.ny));
  return {probe_voxel(x, c.spacing), probe_voxel(y, c.spacing), probe_voxel(z, c.spacing)};
}

inline Vec3 position_of(const Voxels& v, const CascadePlan& c, std::uint64_t q) {
  const std::array<int, 3> cell = probe_cell(c, q);
  return v.centre(cell[0], cell[1], cell[2]);
}

// Whether the probe's own voxel is free (inside the grid: probes past its end are clamped).
inline bool probe_free(const Voxels& v, const CascadePlan& c, std::uint64_t q) {
  const std::array<int, 3> cell = probe_cell(c, q);
  return !v.opaque(v.index(std::min(cell[0], v.nx - 1), std::min(cell[1], v.ny - 1),
                           std::min(cell[2], v.nz - 1)));
}

}  // namespace penumbra::spaceland::grid
