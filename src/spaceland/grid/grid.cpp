#include "spaceland/grid/grid.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>

#include "core/math.hpp"
#include "core/octahedral.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/color.hpp"
#include "spaceland/probe_light.hpp"

namespace penumbra::spaceland::grid {

namespace {

constexpr int kMaxCascades = 12;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

// The voxel a probe of spacing s sits in, along one axis: the middle of its block.
int probe_voxel(int a, int s) {
  return a * s + s / 2;
}

// The 8 probes of a cascade around world point p and their trilinear weights (corners outside
// the grid clamped onto it).
struct Corners {
  std::array<std::uint64_t, 8> index{};
  std::array<float, 8> w{};
};
Corners corners(const Voxels& v, const CascadePlan& c, Vec3 p) {
  int lo[3];
  float f[3];
  const int n[3] = {c.nx, c.ny, c.nz};
  for (int k = 0; k < 3; ++k) {
    const double g = ((double(p[k]) - v.origin[k]) / v.size - 0.5 - c.spacing / 2) / c.spacing;
    const double a = std::floor(g);
    lo[k] = int(a);
    f[k] = float(g - a);
    if (lo[k] < 0) lo[k] = 0, f[k] = 0;
    if (lo[k] >= n[k] - 1) lo[k] = std::max(0, n[k] - 1), f[k] = 0;
  }
  Corners out;
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
std::array<int, 3> probe_cell(const CascadePlan& c, std::uint64_t q) {
  const int x = int(q % std::uint64_t(c.nx)),
            y = int(q / std::uint64_t(c.nx) % std::uint64_t(c.ny)),
            z = int(q / (std::uint64_t(c.nx) * c.ny));
  return {probe_voxel(x, c.spacing), probe_voxel(y, c.spacing), probe_voxel(z, c.spacing)};
}

Vec3 position_of(const Voxels& v, const CascadePlan& c, std::uint64_t q) {
  const std::array<int, 3> cell = probe_cell(c, q);
  return v.centre(cell[0], cell[1], cell[2]);
}

// Whether the probe's own voxel is free (inside the grid: probes past its end are clamped).
bool probe_free(const Voxels& v, const CascadePlan& c, std::uint64_t q) {
  const std::array<int, 3> cell = probe_cell(c, q);
  return !v.opaque(v.index(std::min(cell[0], v.nx - 1), std::min(cell[1], v.ny - 1),
                           std::min(cell[2], v.nz - 1)));
}

}  // namespace

std::uint64_t CascadePlan::bytes() const {
  return probes() * std::uint64_t(side) * std::uint64_t(side) * sizeof(Rgb);
}

namespace {

// The cascade options' ranges (the voxel size is voxelise's to check).
Status check_cascade_options(const GridOptions& o) {
  if (o.probe_spacing < 1 || o.probe_spacing > 64)
    return Error{"`grid.probe_spacing`: expected 1..64 voxels, found " +
                 std::to_string(o.probe_spacing)};
  const int side = int(std::lround(std::sqrt(double(std::max(0, o.directions)))));
  if (o.directions < 4 || side * side != o.directions || (side & (side - 1)) != 0)
    return Error{
        "`grid.directions`: expected the square of a power of two (4, 16, 64, ...), found " +
        std::to_string(o.directions)};
  if (!std::isfinite(o.interval) || o.interval < 0)
    return Error{"`grid.interval`: expected a length > 0 in world units (0: derived), found " +
                 io::format_number(o.interval)};
  if (o.cascades < 0 || o.cascades > kMaxCascades)
    return Error{"`grid.cascades`: expected 0..12 (0: derived), found " +
                 std::to_string(o.cascades)};
  if (o.fix && o.extend_length > 0)
    return Error{
        "`grid.extend_length`: extension doubles a probe's own intervals, which the bilinear fix "
        "does not use (it traces to the upper probes instead): use one or the other"};
  if (!std::isfinite(o.extend_length) || o.extend_length < 0 ||
      (o.extend_length > 0 && o.extend_length < 1))
    return Error{
        "`grid.extend_length`: expected a traced length of at least 1 voxel (0: no "
        "extension), found " +
        io::format_number(o.extend_length)};
  return {};
}

}  // namespace

Expected<std::vector<CascadePlan>> plan_cascades(const Voxels& v, const GridOptions& o) {
  if (Status s = check_cascade_options(o); !s) return s.error();
  const int side = int(std::lround(std::sqrt(double(o.directions))));
  // Four probe spacings: the upper probes' spacing stays a half of the distance where their
  // interval starts. At one spacing (twice the distance) shadows wash out: a probe in an umbra
  // takes the light its upper neighbours beside the occluder see (measured, docs/QUALITY.md).
  const float t0 = o.interval > 0 ? o.interval : 4 * float(o.probe_spacing) * v.size;
  const double diagonal =
      double(v.size) * std::sqrt(double(v.nx) * v.nx + double(v.ny) * v.ny + double(v.nz) * v.nz);
  int n = o.cascades;
  if (n == 0) {
    n = 1;
    while (n < kMaxCascades && double(t0) * double(1 << (n - 1)) < diagonal) ++n;
  }
  std::vector<CascadePlan> plan;
  for (int i = 0; i < n; ++i) {
    CascadePlan c;
    c.spacing = o.probe_spacing << i;
    c.nx = (v.nx + c.spacing - 1) / c.spacing;
    c.ny = (v.ny + c.spacing - 1) / c.spacing;
    c.nz = (v.nz + c.spacing - 1) / c.spacing;
    c.side = side << i;
    c.t_start = i == 0 ? 0.0f : t0 * float(1 << (i - 1));
    c.t_end = i == n - 1 ? kInfinity : t0 * float(1 << i);
    plan.push_back(c);
  }
  return plan;
}

int extension_doublings(const CascadePlan& c, const GridOptions& o, float voxel, bool top) {
  if (top || o.fix || o.extend_length <= 0) return 0;
  const double len = double(c.t_end - c.t_start) / voxel;
  int n = 0;
  while (n < 20 && len / double(1 << n) > double(o.extend_length) * (1 + 1e-6)) ++n;
  return n;
}

std::uint64_t cascades_bytes(const std::vector<CascadePlan>& plan, const GridOptions& o,
                             float voxel) {
  std::uint64_t need = 0;
  for (std::size_t i = 0; i < plan.size(); ++i) {
    // Extending holds the cascade's intervals and transmittances twice (a doubling reads one
    // pair and writes the other) and a byte a ray, besides its merged radiance.
    const bool top = i + 1 == plan.size();
    const std::uint64_t rays = plan[i].bytes() / sizeof(Rgb);
    const std::uint64_t extension =
        extension_doublings(plan[i], o, voxel, top) > 0 ? rays * (4 * sizeof(Rgb) + 1) : 0;
    need = std::max(need,
                    plan[i].bytes() + extension + (i + 1 < plan.size() ? plan[i + 1].bytes() : 0));
  }
  return need;
}

namespace {

// A cascade's intervals traced short and doubled by extension (seed 001 eq. 16):
// L_[a, a+2x](p) = L_[a, a+x](p) + T_[a, a+x](p) L_[a, a+x](p + x w), and T likewise, where the
// shifted interval comes trilinearly from the cascade's own probes of the same direction (a point
// past the grid's box sees nothing along w: the box is convex). `before` marks the rays with a
// surface between the probe and the interval's start.
struct Extended {
  std::vector<Rgb> radiance, transmittance;
  std::vector<std::uint8_t> before;
};

// What a ray sees along a segment and, where the segment does not end on a surface, `beyond` it
// through the segment's transmittance.
Rgb then(const Segment& s, Rgb beyond) {
  return s.blocked ? s.radiance : s.radiance + s.transmittance * beyond;
}

// Calls ray(q, p, d, k) for every probe q of cascade c (at world position p) and direction d
// (k = q * nd + d), rows of probes in parallel.
template <class Ray>
void for_each_ray(const Voxels& v, const CascadePlan& c, std::size_t nd, Ray&& ray) {
  parallel_for(int(c.probes() / std::uint64_t(c.nx)), [&](int row) {
    for (int x = 0; x < c.nx; ++x) {
      const std::uint64_t q = std::uint64_t(row) * c.nx + x;
      const Vec3 p = position_of(v, c, q);
      for (std::size_t d = 0; d < nd; ++d) ray(q, p, d, std::size_t(q) * nd + d);
    }
  });
}

Extended extend_cascade(const Voxels& v, const CascadePlan& c, const std::vector<Vec3>& dirs,
                        int doublings) {
  const std::size_t nd = dirs.size(), count = std::size_t(c.probes());
  Extended e;
  e.radiance.resize(count * nd);
  e.transmittance.resize(count * nd);
  e.before.assign(count * nd, 0);
  const float piece = (c.t_end - c.t_start) / float(1 << doublings);
  for_each_ray(v, c, nd, [&](std::uint64_t, Vec3 p, std::size_t d, std::size_t k) {
    if (c.t_start > 0) e.before[k] = march(v, p, dirs[d], 0, c.t_start).blocked;
    const Segment s = march(v, p, dirs[d], c.t_start, c.t_start + piece);
    e.radiance[k] = s.radiance;
    e.transmittance[k] = s.blocked ? Rgb{} : s.transmittance;
  });
  const double box[3] = {double(v.nx) * v.size, double(v.ny) * v.size, double(v.nz) * v.size};
  std::vector<Rgb> radiance(count * nd), transmittance(count * nd);
  for (int j = 0; j < doublings; ++j) {
    const float shift = piece * float(1 << j);
    for_each_ray(v, c, nd, [&](std::uint64_t, Vec3 p, std::size_t d, std::size_t k) {
      radiance[k] = e.radiance[k];
      transmittance[k] = e.transmittance[k];
      if (is_black(e.transmittance[k])) return;
      const Vec3 at = p + dirs[d] * shift;
      for (int a = 0; a < 3; ++a) {
        const double u = double(at[a]) - v.origin[a];
        if (u < 0 || u > box[a]) return;  // nothing out there: T = 1, no light
      }
      const Corners around = corners(v, c, at);
      Rgb l{}, t{};
      for (int a = 0; a < 8; ++a) {
        const float w = around.w[std::size_t(a)];
        if (w <= 0) continue;
        const std::size_t kk = std::size_t(around.index[std::size_t(a)]) * nd + d;
        l += e.radiance[kk] * w;
        t += e.transmittance[kk] * w;
      }
      radiance[k] += e.transmittance[k] * l;
      transmittance[k] *= t;
    });
    std::swap(radiance, e.radiance);
    std::swap(transmittance, e.transmittance);
  }
  return e;
}

}  // namespace

Expected<Solution> solve(const Voxels& v, const Background& bg, const GridOptions& o,
                         std::uint64_t max_bytes) {
  Expected<std::vector<CascadePlan>> planned = plan_cascades(v, o);
  if (!planned) return planned.error();
  const std::vector<CascadePlan>& plan = *planned;
  const std::uint64_t need = cascades_bytes(plan, o, v.size);
  if (need > max_bytes)
    return Error{"the probe grid's cascades need " +
                 io::format_rounded(double(need) / double(1 << 20)) +
                 " MiB, more than the `max_memory` limit of " +
                 io::format_rounded(double(max_bytes) / double(1 << 20)) +
                 " MiB; use a larger --voxel or fewer --directions"};

  std::vector<Rgb> upper, lower;
  std::vector<Vec3> dirs, up_dirs;  // this cascade's directions and the one above's
  std::vector<double> ms(plan.size());
  for (int i = int(plan.size()) - 1; i >= 0; --i) {
    Stopwatch watch;
    const CascadePlan& c = plan[std::size_t(i)];
    const bool top = i == int(plan.size()) - 1;
    dirs = octahedral::map_directions(c.side);
    const std::size_t nd = dirs.size();
    const std::uint64_t count = c.probes();
    lower.assign(std::size_t(count) * nd, Rgb{});
    const CascadePlan* up = top ? nullptr : &plan[std::size_t(i) + 1];
    const int up_side = top ? 0 : up->side;
    // The fix traces from each interval's start to the upper probes': no ray needs to know
    // whether a surface lies before its interval.
    const bool fix = o.fix && !top;
    const int doublings = extension_doublings(c, o, v.size, top);
    const Extended ext = doublings > 0 ? extend_cascade(v, c, dirs, doublings) : Extended{};
    // What an upper probe sends along its child direction ud (for the fix: all of them).
    auto upper_at = [&](std::uint64_t q, std::size_t ud) -> const Rgb& {
      return upper[std::size_t(q) * (std::size_t(up_side) * up_side) + ud];
    };
    parallel_for(c.nz, [&](int z) {
      for (int y = 0; y < c.ny; ++y)
        for (int x = 0; x < c.nx; ++x) {
          const std::uint64_t q = (std::uint64_t(z) * c.ny + y) * c.nx + x;
          Rgb* out = &lower[std::size_t(q) * nd];
          // A probe inside a surface serves no one (those above: no probe below sees it).
          if (!probe_free(v, c, q)) {
            std::fill(out, out + nd, kNoLight);
            continue;
          }
          const Vec3 p = position_of(v, c, q);
          Corners around;
          Vec3 upper_probe[8];
          if (!top) {
            around = corners(v, *up, p);
            // An upper probe this one cannot see (across a wall or a floor) would bring light
            // from the other side: it takes no part (the 2D cascades weigh by visibility too).
            // With the fix, neither does one inside a surface (it holds no light).
            for (int j = 0; j < 8; ++j) {
              float& w = around.w[std::size_t(j)];
              if (w <= 0) continue;
              const std::uint64_t uq = around.index[std::size_t(j)];
              upper_probe[j] = position_of(v, *up, uq);
              const Vec3 to = upper_probe[j] - p;
              const float dist = length(to);
              if (dist > 0 && march(v, p, to * (1 / dist), 0, dist).blocked) w = 0;
              if (fix && !holds_light(upper_at(uq, 0))) w = 0;
            }
          }
          for (int dv = 0; dv < c.side; ++dv)
            for (int du = 0; du < c.side; ++du) {
              const std::size_t d = std::size_t(dv) * c.side + du;
              const Vec3 dir = dirs[d];
              if (fix) {
                // Each child direction to each upper probe's interval start, then that probe's
                // light along the child direction.
                Rgb sum{};
                float weight = 0;
                for (int j = 0; j < 8; ++j) {
                  const float w = around.w[std::size_t(j)];
                  const std::uint64_t uq = around.index[std::size_t(j)];
                  if (w <= 0) continue;
                  Rgb mean{};
                  for (int cv = 0; cv < 2; ++cv)
                    for (int cu = 0; cu < 2; ++cu) {
                      const std::size_t ud = std::size_t(2 * dv + cv) * std::size_t(up_side) +
                                             std::size_t(2 * du + cu);
                      const Vec3 from = p + up_dirs[ud] * c.t_start;
                      const Vec3 to = upper_probe[j] + up_dirs[ud] * up->t_start - from;
                      const float dist = length(to);
                      mean += then(dist > 0 ? march(v, from, to * (1 / dist), 0, dist) : Segment{},
                                   upper_at(uq, ud));
                    }
                  sum += mean * (w / 4);
                  weight += w;
                }
                if (weight > 0) {
                  out[d] = sum * (1 / weight);
                  continue;
                }
                // No upper probe seen: the ray traces its interval and on to the sky.
                out[d] = then(march(v, p, dir, c.t_start, kInfinity), bg.sky(dir));
                continue;
              }
              // From the probe to the interval's start: a surface there leaves this ray
              // unusable for the cascade below.
              Segment s;
              if (doublings > 0) {
                const std::size_t k = std::size_t(q) * nd + d;
                if (ext.before[k]) {
                  out[d] = kNoLight;
                  continue;
                }
                s.radiance = ext.radiance[k];
                s.transmittance = ext.transmittance[k];
                s.blocked = is_black(s.transmittance);
              } else {
                if (!o.fix && c.t_start > 0 && march(v, p, dir, 0, c.t_start).blocked) {
                  out[d] = kNoLight;
                  continue;
                }
                s = march(v, p, dir, c.t_start, c.t_end);
              }
              if (s.blocked || top) {
                out[d] = then(s, bg.sky(dir));
                continue;
              }
              // The upper probes around this one, each through the mean of its 2x2 children of
              // this direction that hold light.
              Rgb sum{};
              float weight = 0;
              for (int j = 0; j < 8; ++j) {
                const float w = around.w[std::size_t(j)];
                if (w <= 0) continue;
                Rgb mean{};
                int n = 0;
                for (int cv = 0; cv < 2; ++cv)
                  for (int cu = 0; cu < 2; ++cu) {
                    const std::size_t ud =
                        std::size_t(2 * dv + cv) * std::size_t(up_side) + std::size_t(2 * du + cu);
                    const Rgb& u = upper_at(around.index[std::size_t(j)], ud);
                    if (!holds_light(u)) continue;
                    mean += u;
                    ++n;
                  }
                if (n == 0) continue;
                sum += mean * (w / float(n));
                weight += w;
              }
              if (weight > 0) {
                out[d] = s.radiance + s.transmittance * (sum * (1 / weight));
                continue;
              }
              // No upper probe has light this way: the ray continues itself to the sky.
              out[d] = then(s, then(march(v, p, dir, c.t_end, kInfinity), bg.sky(dir)));
            }
        }
    });
    std::swap(upper, lower);
    std::swap(up_dirs, dirs);
    ms[std::size_t(i)] = watch.ms();
  }

  Solution sol;
  sol.cascade_ms_ = std::move(ms);
  sol.voxels_ = &v;
  sol.plan_ = plan;
  sol.dirs_ = std::move(up_dirs);  // cascade 0's, swapped up last
  sol.radiance_ = std::move(upper);
  const std::size_t nd = sol.dirs_.size();
  sol.valid_.resize(std::size_t(plan[0].probes()));
  sol.sphere_.resize(std::size_t(plan[0].probes()));
  const std::uint64_t row = std::uint64_t(plan[0].nx);
  parallel_for(int(plan[0].probes() / row), [&](int r) {
    for (std::uint64_t q = std::uint64_t(r) * row; q < std::uint64_t(r + 1) * row; ++q) {
      sol.valid_[std::size_t(q)] = probe_free(v, plan[0], q);
      if (!sol.valid_[std::size_t(q)]) continue;
      // Equal-area cells: the plain mean is the mean over the sphere.
      Rgb sum{};
      for (std::size_t d = 0; d < nd; ++d) sum += sol.radiance_[std::size_t(q) * nd + d];
      sol.sphere_[std::size_t(q)] = sum * (1 / float(nd));
    }
  });
  return sol;
}

namespace {

// The weighted mean of what the cascade-0 probes around p give: a tent of `radius` probe
// spacings, the 8 probes around p (trilinear weights) first, then 2 and up to `max_radius`
// spacings where none of those serves. `serve(q, probe, value)` says whether probe q (at world
// position `probe`, outside opaque voxels) takes part, and with what value.
template <class Serve>
bool tent(const Voxels& v, const CascadePlan& c, const std::vector<std::uint8_t>& valid, Vec3 p,
          int max_radius, Serve&& serve, Rgb& out) {
  const int dims[3] = {c.nx, c.ny, c.nz};
  // p's continuous probe coordinates (probe a at a).
  double g[3];
  for (int k = 0; k < 3; ++k)
    g[k] = ((double(p[k]) - v.origin[k]) / v.size - 0.5 - c.spacing / 2) / c.spacing;
  for (int radius = 1; radius <= max_radius; radius *= 2) {
    int lo[3];
    for (int k = 0; k < 3; ++k) lo[k] = int(std::floor(g[k])) - (radius - 1);
    Rgb sum{};
    float weight = 0;
    for (int dz = 0; dz < 2 * radius; ++dz)
      for (int dy = 0; dy < 2 * radius; ++dy)
        for (int dx = 0; dx < 2 * radius; ++dx) {
          const int at[3] = {lo[0] + dx, lo[1] + dy, lo[2] + dz};
          float w = 1;
          for (int k = 0; k < 3; ++k) {
            if (at[k] < 0 || at[k] >= dims[k]) w = 0;
            w *= std::max(0.0f, float(1 - std::abs(g[k] - at[k]) / radius));
          }
          if (w <= 0) continue;
          const std::uint64_t q = (std::uint64_t(at[2]) * c.ny + at[1]) * c.nx + at[0];
          if (!valid[std::size_t(q)]) continue;
          Rgb value;
          if (!serve(q, position_of(v, c, q), value)) continue;
          sum += value * w;
          weight += w;
        }
    if (weight > 0) {
      out = sum * (1 / weight);
      return true;
    }
  }
  return false;
}

}  // namespace

bool Solution::sphere_radiance(Vec3 p, Rgb& out) const {
  const Voxels& v = *voxels_;
  const int vdims[3] = {v.nx, v.ny, v.nz};
  int own[3];
  for (int k = 0; k < 3; ++k) own[k] = std::clamp(v.cell(p, k), 0, vdims[k] - 1);
  auto serve = [&](std::uint64_t q, Vec3 probe, Rgb& value) {
    // Marched from the probe: the only opaque voxel it may meet is p's own (p close to a surface
    // lies in the surface's voxels).
    const Vec3 to = p - probe;
    const float dist = length(to);
    if (dist > 0) {
      const Vec3 dir = to * (1 / dist);
      const Segment s = march(v, probe, dir, 0, dist);
      if (s.blocked) {
        const Vec3 in = probe + dir * (s.t_end + 1e-3f * v.size);
        for (int k = 0; k < 3; ++k)
          if (v.cell(in, k) != own[k]) return false;
      }
    }
    value = sphere_[std::size_t(q)];
    return true;
  };
  return tent(v, plan_[0], valid_, p, 2, serve, out);
}

bool Solution::mean_radiance(Vec3 p, Vec3 n, Rgb& out, const RayScene* rays) const {
  const Voxels& v = *voxels_;
  const std::size_t nd = dirs_.size();
  // Without exact rays: the free voxel nearest p in front of its surface (within 2 voxels each
  // way), whose centre probes must see; p itself lies in its surface's opaque voxels (near an
  // edge, in the other surface's too, so a step along the normal alone may not leave them).
  Vec3 free_point = p + n * (2 * v.size);
  if (!rays) {
    int at[3];
    const int vdims[3] = {v.nx, v.ny, v.nz};
    for (int k = 0; k < 3; ++k) at[k] = v.cell(p, k);
    float best = kInfinity;
    for (int dz = -2; dz <= 2; ++dz)
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          const int q[3] = {at[0] + dx, at[1] + dy, at[2] + dz};
          if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= vdims[0] || q[1] >= vdims[1] ||
              q[2] >= vdims[2] || v.opaque(v.index(q[0], q[1], q[2])))
            continue;
          const Vec3 centre = v.centre(q[0], q[1], q[2]);
          const float d = length(centre - p);
          if (dot(centre - p, n) > 0.25f * v.size && d < best) best = d, free_point = centre;
        }
  }
  auto serve = [&](std::uint64_t q, Vec3 probe, Rgb& value) {
    // In front of the surface, and seeing it (from the free point): no light from behind a
    // wall, however thin.
    if (dot(p - probe, n) >= 0) return false;
    if (rays) {
      // The exact surfaces: near an edge the free voxel may lie past the other surface.
      const Vec3 start = rays->spawn(p, n, probe - p);
      if (rays->occluded(Ray{start, probe - start, 0, 1})) return false;
    } else {
      const Vec3 to = probe - free_point;
      const float dist = length(to);
      if (dist > 0 && march(v, free_point, to * (1 / dist), 0, dist).blocked) return false;
    }
    return cosine_mean(
        dirs_, n, [&](std::size_t d) -> const Rgb& { return radiance_[std::size_t(q) * nd + d]; },
        value);
  };
  // Where none of the 8 probes around p serves (they sit in the surface's own voxels, or behind
  // it), up to 4 probe spacings out.
  return tent(v, plan_[0], valid_, p, 4, serve, out);
}

namespace {

// The radiance fog at x scatters, per unit sigma_s: the mean over the sphere (none where no
// probe is seen) and the sun's irradiance spread over 4 pi.
Rgb in_scattered(const Solution& sol, const SunLight* sun, Vec3 x, std::uint64_t& rays) {
  Rgb in{};
  sol.sphere_radiance(x, in);
  if (sun && sun->on()) in += sun->at(x, rays) * float(1 / (4 * kPi));
  return in;
}

}  // namespace

std::uint64_t add_bounce(Voxels& v, const Solution& sol, const std::vector<Rgb>& base,
                         const SunLight* sun, std::vector<Vec3>* normals) {
  // Written aside: the solution marches these voxels meanwhile.
  std::vector<Rgb> next(v.emission.size()), minus(v.emission.size());
  std::vector<std::uint8_t> thin(v.emission.size(), 0);
  if (normals) normals->assign(v.emission.size(), Vec3{});
  std::atomic<std::uint64_t> traced{0};
  parallel_for(v.nz, [&](int z) {
    std::uint64_t rays = 0;
    for (int y = 0; y < v.ny; ++y)
      for (int x = 0; x < v.nx; ++x) {
        const std::size_t k = v.index(x, y, z);
        next[k] = minus[k] = base[k];
        const Vec3 centre = v.centre(x, y, z);
        if (!v.opaque(k)) {
          // Fog re-emits what it scatters: sigma_s times the sphere's mean radiance.
          if (is_black(v.extinction[k]) || is_black(v.albedo[k])) continue;
          next[k] += v.extinction[k] * v.albedo[k] * in_scattered(sol, sun, centre, rays);
          continue;
        }
        // The free 6-neighbours: the outward normal points towards them.
        bool open[3][2] = {};
        int thin_axis = -1, thin_count = 0;
        const int at[3] = {x, y, z}, dims[3] = {v.nx, v.ny, v.nz};
        for (int axis = 0; axis < 3; ++axis) {
          for (int side = 0; side < 2; ++side) {
            int q[3] = {at[0], at[1], at[2]};
            q[axis] += side ? 1 : -1;
            open[axis][side] =
                q[axis] >= 0 && q[axis] < dims[axis] && !v.opaque(v.index(q[0], q[1], q[2]));
          }
          if (open[axis][0] && open[axis][1]) thin_axis = axis, ++thin_count;
        }
        // A voxel one voxel thin along two axes (a rod) has no side to tell: it keeps `base`.
        if (thin_count > 1) continue;
        // The light leaving towards one side: albedo times the mean radiance about the normal of
        // the free faces on that side (`drop`: the thin axis's face on the other side), plus the
        // sun's E cos / pi where a shadow ray from one voxel out along that normal reaches it.
        auto reflected = [&](int drop_axis, int drop_side, Vec3& normal) {
          Vec3 n{};
          for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side)
              if (open[axis][side] && !(axis == drop_axis && side == drop_side))
                n[axis] += side ? 1.0f : -1.0f;
          const float len = length(n);
          normal = {};
          if (!(len > 0)) return Rgb{};
          normal = n * (1 / len);
          Rgb out{}, mean;
          if (sol.mean_radiance(centre, normal, mean)) out += v.albedo[k] * mean;
          if (sun) out += sun->reflected(centre + n * v.size, normal, v.albedo[k], rays);
          return out;
        };
        Vec3 normal;
        if (thin_axis < 0) {
          next[k] += reflected(-1, -1, normal);
          minus[k] = next[k];
        } else {
          // Both sides: towards + (the - face dropped) and towards -.
          Vec3 other;
          next[k] += reflected(thin_axis, 0, normal);
          minus[k] += reflected(thin_axis, 1, other);
          thin[k] = std::uint8_t(1 + thin_axis);
        }
        if (normals) (*normals)[k] = normal;
      }
    traced.fetch_add(rays, std::memory_order_relaxed);
  });
  v.emission = std::move(next);
  v.emission_minus = std::move(minus);
  v.thin = std::move(thin);
  return traced.load();
}

Rgb RadianceCache::reflected(Vec3 p, Vec3 n) const {
  const Voxels& v = voxels_;
  int at[3];
  const int dims[3] = {v.nx, v.ny, v.nz};
  for (int k = 0; k < 3; ++k) at[k] = v.cell(p, k);
  float best = kInfinity;
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
        Vec3 normal = normals_[k];
        bool minus = false;
        if (v.thin[k]) {
          const int axis = v.thin[k] - 1;
          minus = n[axis] < 0;
          if (minus) normal[axis] = -normal[axis];
        }
        if (!(dot(normal, n) > 0.5f)) continue;
        const float d = float(dx * dx + dy * dy + dz * dz);
        if (d < best) best = d, out = minus ? reflected_minus_[k] : reflected_[k];
      }
  return out;
}

Expected<RadianceCache> radiance_cache(const Scene& scene, const RayScene& rays,
                                       const RenderOptions& options, int bounces) {
  if (bounces < 1) return Error{"the radiance cache holds at least one bounce"};
  Expected<Voxels> voxels = voxelise(scene, voxel_size(scene, options), options.max_memory / 4);
  if (!voxels) return voxels.error();
  const Background bg(scene);
  const std::uint64_t left =
      options.max_memory - std::min(options.max_memory, voxel_bytes(voxels->count(), true));
  RadianceCache cache;
  cache.voxels_ = std::move(*voxels);
  Voxels& v = cache.voxels_;
  const std::vector<Rgb> base = v.emission;
  const SunLight sun(scene, rays);
  for (int b = 0; b < bounces; ++b) {
    Expected<Solution> sol = solve(v, bg, options.grid, left);
    if (!sol) return sol.error();
    add_bounce(v, *sol, base, &sun, &cache.normals_);
  }
  cache.reflected_.resize(base.size());
  cache.reflected_minus_.resize(base.size());
  for (std::size_t k = 0; k < base.size(); ++k) {
    cache.reflected_[k] = v.emission[k] - base[k];
    cache.reflected_minus_[k] = v.emission_minus[k] - base[k];
  }
  // Lookups need only where the surfaces are (the extinction's opaque mark) and the thin walls.
  std::vector<Rgb>().swap(v.emission);
  std::vector<Rgb>().swap(v.emission_minus);
  std::vector<Rgb>().swap(v.albedo);
  std::vector<std::uint8_t>().swap(v.skip);
  return cache;
}

Status check_options(const GridOptions& o) {
  if (!std::isfinite(o.voxel) || o.voxel < 0)
    return Error{"`grid.voxel`: expected a voxel size > 0 in world units (0: derived), found " +
                 io::format_number(o.voxel)};
  return check_cascade_options(o);
}

float voxel_size(const Scene& scene, const RenderOptions& options) {
  return options.grid.voxel > 0 ? options.grid.voxel
                                : default_voxel_size(scene, options.max_memory / 4);
}

namespace {

// The light reaching the camera along pixel k's ray: `behind` (what its hit, or the sky, sends)
// through the fog, plus what the fog emits and scatters towards the camera, integrated a step's
// length at a time (Beer-Lambert within each step, the in-scattered radiance at its middle).
Rgb through_fog(const Media& media, const Solution& sol, const SunLight& sun, float step,
                Vec3 origin, Vec3 dir, float t_end, Rgb behind, std::vector<MediumPiece>& pieces,
                std::uint64_t& rays) {
  media.pieces(Ray{origin, dir, 0, t_end}, t_end, pieces);
  Rgb l{}, tr{1, 1, 1};
  for (const MediumPiece& piece : pieces) {
    const float len = piece.t1 - piece.t0;
    if (!(len > 0)) continue;
    const int steps = int(std::clamp(std::ceil(double(len) / step), 1.0, 4096.0));
    const float dt = len / float(steps);
    const Rgb& sigma = piece.sigma_t;
    const Rgb through = exp_neg(sigma * dt);
    for (int i = 0; i < steps; ++i) {
      const Vec3 x = origin + dir * (piece.t0 + (float(i) + 0.5f) * dt);
      const Rgb in = is_black(piece.sigma_s) ? Rgb{} : in_scattered(sol, &sun, x, rays);
      l += tr * stretch_light(sigma, piece.emission + piece.sigma_s * in, dt, through);
      tr *= through;
    }
  }
  return l + tr * behind;
}

}  // namespace

Expected<ImageRgb> render(const Scene& scene, const RayScene& rays, const GBuffer& g,
                          const RenderOptions& options, Stats& stats) {
  Stopwatch watch;
  // A quarter of the limit for the voxels, the rest for the cascades (and what render holds).
  Expected<Voxels> voxels = voxelise(scene, voxel_size(scene, options), options.max_memory / 4);
  if (!voxels) return voxels.error();
  stats.stages.push_back({"voxelise", watch.ms()});
  stats.voxel = voxels->size;
  watch.restart();
  const Background bg(scene);
  const SunLight sun(scene, rays);
  const std::uint64_t voxel_memory = voxel_bytes(voxels->count(), options.bounces > 1);
  const std::uint64_t left = options.max_memory - std::min(options.max_memory, voxel_memory);
  Expected<Solution> sol = solve(*voxels, bg, options.grid, left);
  if (!sol) return sol.error();
  stats.stages.push_back({"cascades", watch.ms()});
  // Later bounces: the surfaces' and the fog's own emission plus what the last solution (and the
  // sun) brings them, solved again (the voxels' light after b bounces gives the pixels b + 1).
  if (options.bounces > 1) {
    const std::vector<Rgb> base = voxels->emission;
    for (int b = 1; b < options.bounces; ++b) {
      watch.restart();
      stats.rays += add_bounce(*voxels, *sol, base, &sun);
      *sol = Solution{};  // its radiance freed before the next solve's
      sol = solve(*voxels, bg, options.grid, left);
      if (!sol) return sol.error();
      stats.stages.push_back({"bounce " + std::to_string(b + 1), watch.ms()});
    }
  }
  stats.cascades = int(sol->cascades().size());
  stats.t0 = sol->cascades()[0].t_end;
  stats.voxel_bytes = voxel_memory;
  stats.memory_bytes = voxel_memory + cascades_bytes(sol->cascades(), options.grid, voxels->size);
  watch.restart();

  ImageRgb img = shade_pixels(g, bg, stats.rays,
                              [&](int, int, std::size_t, const Hit& h, std::uint64_t& local) {
                                const Rgb albedo = albedo_at(scene, h);
                                Rgb l = emission_at(scene, h), mean;
                                if (sol->mean_radiance(h.position, h.geometric_normal, mean, &rays))
                                  l += albedo * mean;
                                return l + sun.reflected(h, albedo, local);
                              });
  const Media media(scene);
  if (!media.empty()) {
    // The fog between the camera and what each pixel shows, a probe spacing a step (the
    // in-scattered light's own resolution).
    const float step = voxels->size * float(options.grid.probe_spacing);
    std::atomic<std::uint64_t> traced{0};
    parallel_for(g.height, [&](int y) {
      std::vector<MediumPiece> pieces;
      std::uint64_t local = 0;
      for (int x = 0; x < g.width; ++x) {
        const std::size_t k = std::size_t(y) * std::size_t(g.width) + std::size_t(x);
        const float t_end = g.found[k] ? g.hits[k].t : kInfinity;
        img.set(x, y,
                through_fog(media, *sol, sun, step, scene.camera.position, g.directions[k], t_end,
                            img.at(x, y), pieces, local));
      }
      traced.fetch_add(local, std::memory_order_relaxed);
    });
    stats.rays += traced.load();
  }
  stats.stages.push_back({"gather", watch.ms()});
  return img;
}

}  // namespace penumbra::spaceland::grid
