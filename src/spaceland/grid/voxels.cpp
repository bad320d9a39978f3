#include "spaceland/grid/voxels.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "io/json_reader.hpp"
#include "spaceland/brdf.hpp"
#include "spaceland/brdf_albedo.hpp"
#include "spaceland/cascade/sphere_lights.hpp"
#include "spaceland/color.hpp"

namespace penumbra::spaceland::grid {

namespace {

constexpr int kPerAxis = 4;  // fog coverage: kPerAxis^3 points a voxel

// Triangle-box overlap by the separating axis theorem (Akenine-Moeller 2001): the box's 3 axes,
// the triangle's normal and the 9 cross products. The box is grown by a hair so that a triangle
// lying exactly on a voxel face counts for the voxels on both sides (conservative).
bool triangle_overlaps_box(const std::array<Vec3, 3>& tri, Vec3 centre, double half) {
  half *= 1 + 1e-5;
  double v[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) v[i][k] = double(tri[std::size_t(i)][k]) - double(centre[k]);
  double e[3][3];
  for (int k = 0; k < 3; ++k) {
    e[0][k] = v[1][k] - v[0][k];
    e[1][k] = v[2][k] - v[1][k];
    e[2][k] = v[0][k] - v[2][k];
  }
  // An axis separates when the triangle's projection lies outside [-r, r], r the box's.
  auto separates = [&](const double a[3]) {
    const double p0 = a[0] * v[0][0] + a[1] * v[0][1] + a[2] * v[0][2];
    const double p1 = a[0] * v[1][0] + a[1] * v[1][1] + a[2] * v[1][2];
    const double p2 = a[0] * v[2][0] + a[1] * v[2][1] + a[2] * v[2][2];
    const double r = half * (std::abs(a[0]) + std::abs(a[1]) + std::abs(a[2]));
    return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
  };
  for (int k = 0; k < 3; ++k) {
    const double axis[3] = {k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0};
    if (separates(axis)) return false;
  }
  const double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                       e[0][0] * e[1][1] - e[0][1] * e[1][0]};
  if (separates(n)) return false;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j) {
      // The box axis k crossed with edge j.
      double a[3] = {0, 0, 0};
      const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
      a[k1] = -e[j][k2];
      a[k2] = e[j][k1];
      if (a[0] == 0 && a[1] == 0 && a[2] == 0) continue;
      if (separates(a)) return false;
    }
  return true;
}

// The area of the triangle's part inside the same box (grown by the same hair, so a triangle on a
// voxel face counts whole on both sides): the triangle clipped by the box's six planes in turn
// (Sutherland-Hodgman), then the polygon's area.
double clipped_area(const std::array<Vec3, 3>& tri, Vec3 centre, double half) {
  half *= 1 + 1e-5;
  // At most 3 + 6 corners in exact arithmetic; room to spare for rounding.
  std::array<std::array<double, 3>, 16> poly{}, next{};
  int count = 3;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k)
      poly[std::size_t(i)][std::size_t(k)] = double(tri[std::size_t(i)][k]) - centre[k];
  for (int plane = 0; plane < 6 && count > 0; ++plane) {
    const std::size_t axis = std::size_t(plane / 2);
    const double sign = (plane % 2) ? -1.0 : 1.0;  // keeps sign * p[axis] <= half
    int out = 0;
    for (int i = 0; i < count; ++i) {
      const std::array<double, 3>& a = poly[std::size_t(i)];
      const std::array<double, 3>& b = poly[std::size_t((i + 1) % count)];
      const double da = half - sign * a[axis], db = half - sign * b[axis];
      if (out + 2 > int(next.size())) break;
      if (da >= 0) next[std::size_t(out++)] = a;
      if ((da >= 0) != (db >= 0)) {
        const double t = da / (da - db);
        for (std::size_t k = 0; k < 3; ++k) next[std::size_t(out)][k] = a[k] + t * (b[k] - a[k]);
        ++out;
      }
    }
    count = out;
    poly = next;
  }
  double n[3] = {0, 0, 0};
  for (int i = 1; i + 1 < count; ++i) {
    const std::array<double, 3>&a = poly[0], &b = poly[std::size_t(i)],
                             &c = poly[std::size_t(i + 1)];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] += u[1] * w[2] - u[2] * w[1];
    n[1] += u[2] * w[0] - u[0] * w[2];
    n[2] += u[0] * w[1] - u[1] * w[0];
  }
  return 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

// Distances from p to the nearest and the farthest point of the box [lo, hi].
double nearest_distance(Vec3 p, Vec3 lo, Vec3 hi) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::max({double(lo[k]) - p[k], 0.0, double(p[k]) - hi[k]});
    s += d * d;
  }
  return std::sqrt(s);
}
double farthest_distance(Vec3 p, Vec3 lo, Vec3 hi) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::max(std::abs(double(lo[k]) - p[k]), std::abs(double(hi[k]) - p[k]));
    s += d * d;
  }
  return std::sqrt(s);
}

// Accumulates, per voxel, the surfaces' area-weighted emission and albedo, and the emitters' area.
struct SurfaceSums {
  std::vector<float> weight, emitting;
  std::vector<Rgb> emission, albedo;
};

// A texture's mean texel (white where there is none): a voxel is far coarser than a texel.
Rgb mean_texel(const Scene& scene, const TextureRef& ref) {
  if (ref.index < 0) return {1, 1, 1};
  const Texture& t = scene.textures[std::size_t(ref.index)];
  double sum[3] = {0, 0, 0};
  for (std::size_t k = 0; k < t.rgb.size(); ++k) sum[k % 3] += t.rgb[k];
  const double n = std::max<std::size_t>(1, t.rgb.size() / 3);
  return {float(sum[0] / n), float(sum[1] / n), float(sum[2] / n)};
}

// Each material's albedo and emission times their textures' mean texels; a glossy material's
// albedo is the share of a uniform light it reflects (hemispherical_albedo), its metallic and
// roughness times their texture's mean.
std::vector<Rgb> mean_albedos(const Scene& scene) {
  std::vector<Rgb> out;
  for (const Material& m : scene.materials) {
    const Rgb base = m.albedo * mean_texel(scene, m.albedo_texture);
    if (m.lambertian()) {
      out.push_back(base);
      continue;
    }
    const Rgb mr = mean_texel(scene, m.metallic_roughness_texture);
    out.push_back(hemispherical_albedo(make_brdf(base, m.metallic * mr.b, m.roughness * mr.g)));
  }
  return out;
}
std::vector<Rgb> mean_emissions(const Scene& scene) {
  std::vector<Rgb> out;
  for (const Material& m : scene.materials)
    out.push_back(m.emission * mean_texel(scene, m.emission_texture));
  return out;
}

// The axis-aligned bounds of a fog box (its 8 corners).
Bounds box_bounds(const Medium& m) {
  Bounds b{m.center, m.center};
  for (int c = 0; c < 8; ++c) {
    Vec3 p = m.center;
    for (int k = 0; k < 3; ++k)
      p = p + m.axes[std::size_t(k)] * (((c >> k) & 1) ? m.half_size[k] : -m.half_size[k]);
    b.lo = min(b.lo, p);
    b.hi = max(b.hi, p);
  }
  return b;
}

}  // namespace

std::uint64_t voxel_bytes(std::uint64_t n, bool sides) {
  // With bounces: each thin wall's second value and mark, the surfaces' own emission kept aside,
  // and add_bounce's new emission, second values and marks while the old ones live.
  const std::uint64_t bounce = 4 * sizeof(Rgb) + 2 * sizeof(std::uint8_t);
  return n * (3 * sizeof(Rgb) + sizeof(std::uint8_t) + (sides ? bounce : 0));
}

Bounds grid_bounds(const Scene& scene) {
  Bounds b = scene_bounds(scene);
  bool any = !scene.meshes.empty() || !scene.spheres.empty() || !scene.disks.empty();
  for (const Medium& m : scene.media) {
    const Bounds mb = box_bounds(m);
    b.lo = any ? min(b.lo, mb.lo) : mb.lo;
    b.hi = any ? max(b.hi, mb.hi) : mb.hi;
    any = true;
  }
  return b;
}

std::array<double, 3> grid_dims(const Bounds& b, double size) {
  std::array<double, 3> d;
  for (int k = 0; k < 3; ++k)
    d[std::size_t(k)] = std::ceil(std::max(double(b.hi[k]) - b.lo[k], 0.0) / size) + 2 * kPadding;
  return d;
}

float default_voxel_size(const Scene& scene, std::uint64_t max_bytes) {
  const Bounds b = grid_bounds(scene);
  const Vec3 e = b.hi - b.lo;
  const double longest = std::max({double(e.x), double(e.y), double(e.z), 1e-6});
  double size = longest / 128;
  auto bytes = [&](double s) {
    const std::array<double, 3> d = grid_dims(b, s);
    return double(voxel_bytes(1)) * d[0] * d[1] * d[2];
  };
  while (bytes(size) > double(max_bytes)) size *= 1.25;
  return float(size);
}

namespace {

// The voxel range [lo, hi] (inclusive, clamped to the grid) that a box of world corners [a, c]
// touches, a voxel more on every side.
void voxel_range(const Voxels& v, Vec3 a, Vec3 c, std::array<int, 3>& lo, std::array<int, 3>& hi) {
  const int dim[3] = {v.nx, v.ny, v.nz};
  for (int k = 0; k < 3; ++k) {
    lo[std::size_t(k)] = std::clamp(v.cell(a, k) - 1, 0, dim[k] - 1);
    hi[std::size_t(k)] = std::clamp(v.cell(c, k) + 1, 0, dim[k] - 1);
  }
}

// The lowest corner of voxel (x, y, z).
Vec3 voxel_lo(const Voxels& v, int x, int y, int z) {
  return v.origin + Vec3{float(x) * v.size, float(y) * v.size, float(z) * v.size};
}

// The empty grid of voxels of `size` over the scene's bounds (or `box`, a part of them), refused
// when an axis or the whole passes what memory allows.
Expected<Voxels> empty_grid(const Scene& scene, float size, std::uint64_t max_bytes,
                            const VoxelBox* box) {
  if (!(size > 0) || !std::isfinite(size))
    // Given sizes were checked with the options; this one may be derived from the scene.
    return Error{
        "the voxel size (`grid.voxel`, or derived from the scene's size) must be a "
        "number > 0 in world units, found " +
        io::format_number(size)};
  const Bounds b = grid_bounds(scene);
  Voxels v;
  v.size = size;
  v.origin = b.lo - Vec3{size, size, size} * float(kPadding);
  double n = 1;
  int dims[3];
  const std::array<double, 3> counts = grid_dims(b, size);
  for (int k = 0; k < 3; ++k) {
    const double cells = box ? double(box->dims[std::size_t(k)]) : counts[std::size_t(k)];
    if (cells > double(1 << 20))
      return Error{"the voxel size " + io::format_number(size) +
                   " (`grid.voxel`, or derived) makes " + io::format_number(cells) +
                   " voxels along an axis; use a larger --voxel"};
    dims[k] = int(cells);
    n *= cells;
    if (box) v.origin[k] += float(box->first[std::size_t(k)]) * size;
  }
  if (double(voxel_bytes(1)) * n > double(max_bytes))
    return Error{"the voxel grid (" + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) +
                 " x " + std::to_string(dims[2]) + " voxels of " + io::format_number(size) +
                 ") needs " + io::format_rounded(double(voxel_bytes(1)) * n / double(1 << 20)) +
                 " MiB, more than the `max_memory` limit of " +
                 io::format_rounded(double(max_bytes) / double(1 << 20)) +
                 " MiB; use a larger --voxel"};
  v.nx = dims[0], v.ny = dims[1], v.nz = dims[2];
  const std::size_t count = std::size_t(v.count());
  v.extinction.assign(count, Rgb{});
  v.emission.assign(count, Rgb{});
  v.albedo.assign(count, Rgb{});
  return v;
}

// The voxels each surface touches (conservatively), with its area share.
class SurfaceRaster {
 public:
  SurfaceRaster(const Scene& scene, const Voxels& v) : v_(v) {
    const std::size_t count = std::size_t(v.count());
    sums_.weight.assign(count, 0);
    sums_.emitting.assign(count, 0);
    sums_.emission.assign(count, Rgb{});
    sums_.albedo.assign(count, Rgb{});
    albedos_ = mean_albedos(scene);
    emissions_ = mean_emissions(scene);
  }

  void triangle(const std::array<Vec3, 3>& tri, std::uint32_t material) {
    // A degenerate triangle (a mesh's sliver, its corners on one line but for rounding) covers
    // nothing and stops no light: twice its area under 1e-6 of its longest edge squared.
    double e[3][3], longest = 0;
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c)
        e[k][c] = double(tri[std::size_t((k + 1) % 3)][c]) - double(tri[std::size_t(k)][c]);
      longest = std::max(longest, e[k][0] * e[k][0] + e[k][1] * e[k][1] + e[k][2] * e[k][2]);
    }
    const double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1],
                         e[0][2] * e[1][0] - e[0][0] * e[1][2],
                         e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    if (!(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) > 1e-6 * longest)) return;
    const double half = 0.5 * double(v_.size);
    std::array<int, 3> lo, hi;
    voxel_range(v_, min(tri[0], min(tri[1], tri[2])), max(tri[0], max(tri[1], tri[2])), lo, hi);
    // Each voxel it touches takes its area there (at least a sliver's: a voxel the triangle
    // only grazes is opaque all the same, so no light slips past a wall along a voxel face).
    const float sliver = 1e-6f * v_.size * v_.size;
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x)
          if (triangle_overlaps_box(tri, v_.centre(x, y, z), half))
            add_at(v_.index(x, y, z),
                   std::max(sliver, float(clipped_area(tri, v_.centre(x, y, z), half))), material);
  }

  // A sphere: the voxels its surface passes through (nearest point inside, farthest outside).
  void sphere(const Sphere& s) {
    const Vec3 r{s.radius, s.radius, s.radius};
    std::array<int, 3> lo, hi;
    voxel_range(v_, s.center - r, s.center + r, lo, hi);
    touched_.clear();
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const Vec3 a = voxel_lo(v_, x, y, z), c = a + Vec3{v_.size, v_.size, v_.size};
          if (nearest_distance(s.center, a, c) <= s.radius &&
              farthest_distance(s.center, a, c) >= s.radius)
            touched_.push_back(v_.index(x, y, z));
        }
    add(4 * kPi * double(s.radius) * s.radius * inside(s.center - r, s.center + r), s.material);
  }

  // A disk: the voxels its plane crosses within its radius of its centre (a superset near the
  // rim: conservative).
  void disk(const Disk& d) {
    const Vec3 r{d.radius, d.radius, d.radius};
    std::array<int, 3> lo, hi;
    voxel_range(v_, d.center - r, d.center + r, lo, hi);
    touched_.clear();
    const double reach = 0.5 * double(v_.size) *
                         (std::abs(d.normal.x) + std::abs(d.normal.y) + std::abs(d.normal.z)) *
                         (1 + 1e-5);
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const Vec3 a = voxel_lo(v_, x, y, z), c = a + Vec3{v_.size, v_.size, v_.size};
          const Vec3 mid = v_.centre(x, y, z);
          if (std::abs(double(dot(d.normal, mid - d.center))) <= reach &&
              nearest_distance(d.center, a, c) <= d.radius)
            touched_.push_back(v_.index(x, y, z));
        }
    add(kPi * double(d.radius) * d.radius * inside(d.center - r, d.center + r), d.material);
  }

  // Every voxel a surface touched becomes opaque, with the area-weighted mean albedo. Its emission
  // is the emitters' area-weighted mean diluted by the other surfaces only up to a voxel face's
  // area: a panel a centimetre off its wall shares voxels with it, and as a mean it glowed half
  // as bright, while a light small beside a wall still spreads its power over the voxel's face.
  // Such a voxel glows on both sides: a wall one voxel thick shows the panel to the next room.
  void finish(Voxels& v) const {
    const float face = v.size * v.size;
    for (std::size_t k = 0; k < sums_.weight.size(); ++k) {
      if (!(sums_.weight[k] > 0)) continue;
      v.extinction[k] = {kOpaque, kOpaque, kOpaque};
      v.emission[k] =
          sums_.emission[k] * (1 / std::max(sums_.emitting[k], std::min(sums_.weight[k], face)));
      v.albedo[k] = sums_.albedo[k] * (1 / sums_.weight[k]);
    }
  }

 private:
  // The part of a surface with bounds [lo, hi] that lies in the grid's box, by its bounds' extent
  // along each axis (1 for one grid over the whole scene). A clipmap level holds only part of a
  // wide surface: the area it shares among its voxels is that part, else it would outweigh the
  // surfaces beside it in their voxels.
  double inside(Vec3 lo, Vec3 hi) const {
    double f = 1;
    for (int k = 0; k < 3; ++k) {
      const double len = double(hi[k]) - lo[k];
      if (!(len > 0)) continue;
      const double a = v_.origin[k], b = a + double(v_.size) * (k == 0   ? v_.nx
                                                                : k == 1 ? v_.ny
                                                                         : v_.nz);
      f *= std::clamp((std::min(double(hi[k]), b) - std::max(double(lo[k]), a)) / len, 0.0, 1.0);
    }
    return f;
  }

  // The surface's area shared among the voxels it touched (spheres and disks: evenly).
  void add(double area, std::uint32_t material) {
    if (touched_.empty()) return;
    const float w = float(area / double(touched_.size()));
    for (std::size_t k : touched_) add_at(k, w, material);
  }
  void add_at(std::size_t k, float w, std::uint32_t material) {
    const Rgb e = emissions_[material];
    sums_.weight[k] += w;
    if (!is_black(e)) sums_.emitting[k] += w;
    sums_.emission[k] += e * w;
    sums_.albedo[k] += albedos_[material] * w;
  }

  const Voxels& v_;
  SurfaceSums sums_;
  std::vector<Rgb> albedos_, emissions_;
  std::vector<std::size_t> touched_;
};

void rasterise_surfaces(const Scene& scene, Voxels& v, const std::vector<std::uint8_t>* left_out) {
  SurfaceRaster raster(scene, v);
  for (const TriangleMesh& mesh : scene.meshes)
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      raster.triangle({mesh.positions[mesh.triangles[t][0]], mesh.positions[mesh.triangles[t][1]],
                       mesh.positions[mesh.triangles[t][2]]},
                      mesh.materials[t]);
  // Small sphere lights are not voxels: the cascades spread them (cascade/sphere_lights.hpp).
  for (std::size_t i = 0; i < scene.spheres.size(); ++i) {
    const Sphere& s = scene.spheres[i];
    if (!(left_out ? (*left_out)[i] != 0 : cascade::spread_by_grid(scene, s, v.size)))
      raster.sphere(s);
  }
  for (const Disk& d : scene.disks) raster.disk(d);
  raster.finish(v);
}

// The fraction of voxel (x, y, z) inside fog box m. A voxel wholly inside or outside the box
// along each of its axes is settled from its centre (the voxel's half extent projected on the
// axis); one its faces cross is the product of its overlaps on each axis for a box along the
// world's axes (exact), else the fraction of its kPerAxis^3 points inside.
float covered(const Voxels& v, const Medium& m, int x, int y, int z) {
  const Vec3 a = voxel_lo(v, x, y, z);
  const float h = 0.5f * v.size;
  const Vec3 c = a + Vec3{h, h, h} - m.center;
  bool all_in = true;
  for (int j = 0; j < 3; ++j) {
    const Vec3& axis = m.axes[std::size_t(j)];
    const float d = std::abs(dot(c, axis));
    const float r = h * (std::abs(axis.x) + std::abs(axis.y) + std::abs(axis.z));
    // Margins of float rounding either way: such a voxel is sampled.
    if (d - r > m.half_size[j] * (1 + 1e-5f) + 1e-6f * v.size) return 0;
    all_in = all_in && d + r < m.half_size[j] * (1 - 1e-5f);
  }
  if (all_in) return 1;
  // A box along the world's axes covers the product of its overlaps with the voxel on each axis,
  // exactly (the usual fog box; the faces of thousands of them cost no sampling).
  if (m.axes[0].x == 1 && m.axes[1].y == 1 && m.axes[2].z == 1) {
    double f = 1;
    for (int k = 0; k < 3; ++k) {
      const double lo = std::max(double(a[k]), double(m.center[k]) - m.half_size[k]);
      const double hi = std::min(double(a[k]) + v.size, double(m.center[k]) + m.half_size[k]);
      f *= std::max(0.0, hi - lo) / v.size;
    }
    return float(f);
  }
  int inside = 0;
  for (int i = 0; i < kPerAxis * kPerAxis * kPerAxis; ++i) {
    const Vec3 p = a + Vec3{(float(i % kPerAxis) + 0.5f) / kPerAxis * v.size,
                            (float(i / kPerAxis % kPerAxis) + 0.5f) / kPerAxis * v.size,
                            (float(i / (kPerAxis * kPerAxis)) + 0.5f) / kPerAxis * v.size};
    const Vec3 q = p - m.center;
    bool in = true;
    for (int j = 0; j < 3 && in; ++j)
      in = std::abs(dot(q, m.axes[std::size_t(j)])) <= m.half_size[j];
    inside += in;
  }
  return float(inside) / float(kPerAxis * kPerAxis * kPerAxis);
}

// The voxels of row (y, z) a fog box may touch ([touch_lo, touch_hi]) and those wholly inside it
// ([in_lo, in_hi], empty when in_lo > in_hi), from the box's slabs along the row's line of voxel
// centres: along each of its axes a voxel centre at distance d with half extent r along it is
// outside past half_size + r and inside within half_size - r. Both are widened (touch) or
// narrowed (inside) by a voxel, so that `covered` settles the voxels near each end exactly as it
// would alone.
struct RowSpan {
  int touch_lo, touch_hi, in_lo, in_hi;
};
RowSpan row_span(const Voxels& v, const Medium& m, int y, int z, int x_lo, int x_hi) {
  const double h = 0.5 * v.size;
  const double yc = double(v.origin.y) + (y + 0.5) * v.size - m.center.y;
  const double zc = double(v.origin.z) + (z + 0.5) * v.size - m.center.z;
  // The voxel centre's offset along x from the box centre is X = x0 + x * size.
  const double x0 = double(v.origin.x) + h - m.center.x;
  double out_lo = -1e300, out_hi = 1e300, in_lo = -1e300, in_hi = 1e300;
  for (int j = 0; j < 3; ++j) {
    const Vec3& a = m.axes[std::size_t(j)];
    const double e = double(a.y) * yc + double(a.z) * zc;
    const double r = h * (std::abs(double(a.x)) + std::abs(double(a.y)) + std::abs(double(a.z)));
    const double half = m.half_size[j];
    // |a.x X + e| <= t, for the outer (t = half + r) and inner (t = half - r) slabs.
    for (int inner = 0; inner < 2; ++inner) {
      const double t = inner ? half - r : half + r;
      double& lo = inner ? in_lo : out_lo;
      double& hi = inner ? in_hi : out_hi;
      if (t < 0) {
        lo = 1e300, hi = -1e300;
        continue;
      }
      if (a.x == 0) {
        if (std::abs(e) > t) lo = 1e300, hi = -1e300;
        continue;
      }
      const double p = (-t - e) / a.x, q = (t - e) / a.x;
      lo = std::max(lo, std::min(p, q));
      hi = std::min(hi, std::max(p, q));
    }
  }
  // From X to voxel indices.
  auto index_of = [&](double X) { return std::clamp((X - x0) / v.size, -1e9, 1e9); };
  RowSpan span{x_hi + 1, x_lo - 1, 0, -1};
  if (out_lo <= out_hi) {
    span.touch_lo = std::max(x_lo, int(std::floor(index_of(out_lo))) - 1);
    span.touch_hi = std::min(x_hi, int(std::ceil(index_of(out_hi))) + 1);
  }
  if (in_lo <= in_hi) {
    span.in_lo = std::max(span.touch_lo, int(std::ceil(index_of(in_lo))) + 1);
    span.in_hi = std::min(span.touch_hi, int(std::floor(index_of(in_hi))) - 1);
  }
  return span;
}

// Fog: the coefficients of every box, times the fraction of the voxel it covers (`covered`). Row by
// row: each box adds its wholly covered run of a row through a difference array (two entries)
// and samples only the voxels its faces cross, so thousands of large overlapping boxes cost their
// rows and faces, not their volumes (5,000 boxes of 1-4 units in a 10-unit room took 12 s).
void add_fog(const Scene& scene, Voxels& v) {
  if (scene.media.empty()) return;
  const std::size_t count = std::size_t(v.count());
  std::vector<Rgb> scattering(count, Rgb{});
  struct Box {
    std::array<int, 3> lo, hi;
    Rgb sigma_s;
  };
  std::vector<Box> boxes(scene.media.size());
  // The boxes that reach each z layer (in scene order, so sums run in the same order always).
  std::vector<std::vector<std::uint32_t>> layers(std::size_t(v.nz));
  for (std::size_t b = 0; b < boxes.size(); ++b) {
    const Medium& m = scene.media[b];
    const Bounds mb = box_bounds(m);
    voxel_range(v, mb.lo, mb.hi, boxes[b].lo, boxes[b].hi);
    boxes[b].sigma_s = m.extinction * m.albedo;
    for (int z = boxes[b].lo[2]; z <= boxes[b].hi[2]; ++z)
      layers[std::size_t(z)].push_back(std::uint32_t(b));
  }
  parallel_for(v.nz, [&](int z) {
    const std::vector<std::uint32_t>& here = layers[std::size_t(z)];
    if (here.empty()) return;
    // Running sums of extinction, emission and scattering (9 values) along a row.
    std::vector<double> diff(9 * (std::size_t(v.nx) + 1));
    for (int y = 0; y < v.ny; ++y) {
      int runs = 0;
      double added[9] = {};  // the magnitudes put in: what rounding may leave behind scales so
      for (std::uint32_t b : here) {
        const Box& box = boxes[b];
        if (y < box.lo[1] || y > box.hi[1]) continue;
        const Medium& m = scene.media[b];
        const RowSpan span = row_span(v, m, y, z, box.lo[0], box.hi[0]);
        for (int x = span.touch_lo; x <= span.touch_hi; ++x) {
          if (x >= span.in_lo && x <= span.in_hi) {
            x = span.in_hi;  // the run is added below
            continue;
          }
          const std::size_t k = v.index(x, y, z);
          if (v.opaque(k)) continue;
          const float f = covered(v, m, x, y, z);
          if (f == 0) continue;
          v.extinction[k] += m.extinction * f;
          v.emission[k] += m.emission * f;
          scattering[k] += box.sigma_s * f;
        }
        if (span.in_lo > span.in_hi) continue;
        const Rgb add[3] = {m.extinction, m.emission, box.sigma_s};
        for (int c = 0; c < 9; ++c) {
          const Rgb& a = add[c / 3];
          const double value = double(c % 3 == 0 ? a.r : c % 3 == 1 ? a.g : a.b);
          diff[9 * std::size_t(span.in_lo) + std::size_t(c)] += value;
          diff[9 * (std::size_t(span.in_hi) + 1) + std::size_t(c)] -= value;
          added[c] += std::fabs(value);
        }
        ++runs;
      }
      if (!runs) continue;
      // Runs that ended leave rounding behind (a + b - b): below this, a sum is nothing.
      double tol[9];
      for (int c = 0; c < 9; ++c) tol[c] = 4 * 2.3e-16 * added[c] * runs;
      double sum[9] = {};
      for (int x = 0; x < v.nx; ++x) {
        for (int c = 0; c < 9; ++c) {
          sum[c] += diff[9 * std::size_t(x) + std::size_t(c)];
          diff[9 * std::size_t(x) + std::size_t(c)] = 0;
        }
        const std::size_t k = v.index(x, y, z);
        auto at = [&](int c) { return sum[c] > tol[c] ? float(sum[c]) : 0.0f; };
        if (v.opaque(k)) continue;
        v.extinction[k] += Rgb{at(0), at(1), at(2)};
        v.emission[k] += Rgb{at(3), at(4), at(5)};
        scattering[k] += Rgb{at(6), at(7), at(8)};
      }
      std::fill(diff.begin() + 9 * std::ptrdiff_t(v.nx), diff.end(), 0.0);
    }
  });
  for (std::size_t k = 0; k < count; ++k) {
    if (v.opaque(k)) continue;
    const Rgb& s = v.extinction[k];
    v.albedo[k] = {s.r > 0 ? scattering[k].r / s.r : 0, s.g > 0 ? scattering[k].g / s.g : 0,
                   s.b > 0 ? scattering[k].b / s.b : 0};
  }
}

}  // namespace

Expected<Voxels> voxelise(const Scene& scene, float size, std::uint64_t max_bytes,
                          const VoxelBox* box, const std::vector<std::uint8_t>* left_out) {
  Expected<Voxels> v = empty_grid(scene, size, max_bytes, box);
  if (!v) return v;
  rasterise_surfaces(scene, *v, left_out);
  add_fog(scene, *v);
  build_distance_field(*v);
  return v;
}

void build_distance_field(Voxels& v) {
  // The chessboard distance transform in two raster passes over the 26-neighbourhood (exact for
  // this metric): forward from the 13 neighbours already visited, backward from the other 13.
  const std::size_t count = std::size_t(v.count());
  v.skip.assign(count, 255);
  for (std::size_t k = 0; k < count; ++k)
    if (!is_black(v.extinction[k]) || !is_black(v.emission[k])) v.skip[k] = 0;
  auto pass = [&](int sign) {
    const int z0 = sign > 0 ? 0 : v.nz - 1, y0 = sign > 0 ? 0 : v.ny - 1,
              x0 = sign > 0 ? 0 : v.nx - 1;
    for (int z = z0; z >= 0 && z < v.nz; z += sign)
      for (int y = y0; y >= 0 && y < v.ny; y += sign)
        for (int x = x0; x >= 0 && x < v.nx; x += sign) {
          std::uint8_t& d = v.skip[v.index(x, y, z)];
          if (d == 0) continue;
          int best = d;
          // The neighbours before this voxel in the pass's order.
          for (int dz = -1; dz <= 0; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                if (dz == 0 && (dy > 0 || (dy == 0 && dx >= 0))) continue;
                const int qx = x + sign * dx, qy = y + sign * dy, qz = z + sign * dz;
                if (qx < 0 || qy < 0 || qz < 0 || qx >= v.nx || qy >= v.ny || qz >= v.nz) continue;
                best = std::min(best, v.skip[v.index(qx, qy, qz)] + 1);
              }
          d = std::uint8_t(best);
        }
  };
  pass(1);
  pass(-1);
}

namespace {

// The march within v's box; `enter` and `leave` receive where the ray's line enters and leaves
// the box (enter > leave: it misses it).
Segment march_box(const Voxels& v, Vec3 origin, Vec3 dir, float tmin, float tmax, double& enter,
                  double& leave) {
  Segment out;
  out.t_end = tmax;
  // Clip [tmin, tmax] to the grid's box (slabs).
  enter = -std::numeric_limits<double>::infinity();
  leave = std::numeric_limits<double>::infinity();
  const double dims[3] = {double(v.nx), double(v.ny), double(v.nz)};
  for (int k = 0; k < 3; ++k) {
    const double lo = v.origin[k], hi = lo + dims[k] * v.size;
    if (dir[k] == 0) {
      if (origin[k] < lo || origin[k] > hi) {
        enter = 1, leave = 0;
        return out;
      }
      continue;
    }
    double a = (lo - origin[k]) / dir[k], b = (hi - origin[k]) / dir[k];
    if (a > b) std::swap(a, b);
    enter = std::max(enter, a);
    leave = std::min(leave, b);
  }
  const double t0 = std::max(double(tmin), enter), t1 = std::min(double(tmax), leave);
  if (!(t0 < t1)) return out;
  // The voxel at the entry (the middle of the first step decides it, so that an entry on a
  // face does not round into the neighbour) and the DDA's state.
  int cell[3], step[3];
  double next[3];
  // Where the ray leaves voxel `c` along axis a, always from the same expression (the walk and
  // the leaps over empty space break ties at voxel edges alike).
  auto boundary = [&](int a, int c) {
    return (v.origin[a] + double(c + (step[a] > 0 ? 1 : 0)) * v.size - origin[a]) / dir[a];
  };
  const double probe_t = t0 + 1e-9 * std::max(1.0, std::abs(t0));
  for (int k = 0; k < 3; ++k) {
    const double p = double(origin[k]) + probe_t * dir[k] - v.origin[k];
    cell[k] = std::clamp(int(std::floor(p / v.size)), 0, int(dims[k]) - 1);
    step[k] = dir[k] > 0 ? 1 : dir[k] < 0 ? -1 : 0;
    next[k] = step[k] ? boundary(k, cell[k]) : std::numeric_limits<double>::infinity();
  }
  double t = t0;
  const bool skipping = !v.skip.empty();
  // A leap stops an eighth of a voxel (along every axis at most) before the empty cube's exit.
  const double short_of_exit =
      0.125 * double(v.size) /
      std::max({std::abs(double(dir[0])), std::abs(double(dir[1])), std::abs(double(dir[2]))});
  while (t < t1) {
    const std::size_t k = v.index(cell[0], cell[1], cell[2]);
    if (skipping && v.skip[k] >= 2) {
      // Nothing within d - 1 voxels of this one (chessboard): leap to the last voxel of that
      // cube along the ray, and walk on from there one voxel at a time (a leap straight out of
      // the cube could cut past the corner of a voxel the walk would enter).
      const int r = v.skip[k] - 1;
      double leave = t1;
      for (int a = 0; a < 3; ++a) {
        if (step[a] == 0) continue;
        const double face = v.origin[a] + double(cell[a] + (step[a] > 0 ? r + 1 : -r)) * v.size;
        leave = std::min(leave, (face - origin[a]) / dir[a]);
      }
      if (leave >= t1) break;
      // A point an eighth of a voxel (along every axis at most) before the exit: in one of the
      // cube's voxels the ray crosses last, at least r - 1/8 voxels past this one along the
      // exit's axis (so the leap always moves on).
      const double at = leave - short_of_exit;
      const int from[3] = {cell[0], cell[1], cell[2]};
      for (int a = 0; a < 3; ++a) {
        if (step[a] == 0) continue;
        const double p = double(origin[a]) + at * dir[a] - v.origin[a];
        cell[a] = std::clamp(int(std::floor(p / v.size)), from[a] - r, from[a] + r);
        next[a] = boundary(a, cell[a]);
      }
      t = std::max(t, at);
      continue;
    }
    const int axis = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
    const double leave = std::min(next[axis], t1);
    if (v.opaque(k)) {
      out.radiance += out.transmittance * v.emission_towards(k, dir);
      out.transmittance = {0, 0, 0};
      out.t_end = float(t);
      out.blocked = true;
      return out;
    }
    const float len = float(leave - t);
    const Rgb& s = v.extinction[k];
    const Rgb& e = v.emission[k];
    // An empty voxel leaves the segment as it is (transmittance 1, no light): skip the arithmetic.
    const bool empty = is_black(s) && is_black(e);
    if (len > 0 && !empty) {
      const Rgb pass = exp_neg(s * len);
      out.radiance += out.transmittance * stretch_light(s, e, len, pass);
      out.transmittance *= pass;
    }
    t = leave;
    if (leave >= t1) break;
    cell[axis] += step[axis];
    if (cell[axis] < 0 || cell[axis] >= int(dims[axis])) break;
    next[axis] = boundary(axis, cell[axis]);
  }
  return out;
}

}  // namespace

Segment march(const Voxels& v, Vec3 origin, Vec3 dir, float tmin, float tmax) {
  double enter, leave;
  if (!v.outer) return march_box(v, origin, dir, tmin, tmax, enter, leave);
  // A clipmap level: a ray that starts in its box marches it to where it leaves, then goes on
  // through the coarser levels; one that starts outside sees the coarser levels only (they hold
  // this level's region too, coarser).
  Segment out = march_box(v, origin, dir, tmin, tmax, enter, leave);
  const bool inside = enter <= double(tmin) && double(tmin) < leave;
  if (!inside) return march(*v.outer, origin, dir, tmin, tmax);
  if (out.blocked || !(leave < double(tmax))) return out;
  const Segment rest = march(*v.outer, origin, dir, float(leave), tmax);
  out.radiance += out.transmittance * rest.radiance;
  out.transmittance *= rest.transmittance;
  out.blocked = rest.blocked;
  out.t_end = rest.t_end;
  return out;
}

}  // namespace penumbra::spaceland::grid
