// Reading the probe grid's cascade-0 field at surface points and in fog, and one more bounce.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "spaceland/brdf.hpp"
#include "spaceland/brdf_albedo.hpp"
#include "spaceland/cascade/cone.hpp"
#include "spaceland/cascade/radiance.hpp"
#include "spaceland/cascade/sphere_lights.hpp"
#include "spaceland/color.hpp"
#include "spaceland/grid/grid.hpp"
#include "spaceland/grid/probes.hpp"

namespace penumbra::spaceland::grid {

using cascade::kInfinity;
using cascade::RadianceStore;

// The weighted mean of what cascade i's probes around p give: a tent of `radius` probe
// spacings, the 8 probes around p (trilinear weights) first, then 2 and up to `max_radius`
// spacings where none of those serves. `serve(q, probe, value)` says whether probe q (at world
// position `probe`, outside opaque voxels) takes part, and with what value.
template <class Serve, class T>
bool RadianceField::tent(int i, Vec3 p, int max_radius, Serve&& serve, T& out) const {
  const Voxels& v = *voxels_;
  const CascadePlan& c = plan_[std::size_t(i)];
  const int dims[3] = {c.nx, c.ny, c.nz};
  double g[3];
  for (int k = 0; k < 3; ++k) g[k] = probe_coordinate(v, c.spacing, p, k);
  for (int radius = 1; radius <= max_radius; radius *= 2) {
    int lo[3];
    for (int k = 0; k < 3; ++k) lo[k] = int(std::floor(g[k])) - (radius - 1);
    T sum{};
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
          if (i == 0 ? !valid_[std::size_t(q)] : !probe_free(v, c, q)) continue;
          T value;
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

bool RadianceField::sphere_radiance(Vec3 p, Rgb& out) const {
  const Voxels& v = *voxels_;
  std::vector<cascade::PointLight>& lights = cascade::point_lights();
  lights_at(p, Vec3{}, lights);
  UpperView view{p, Vec3{}, p};
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
    if (!lights.empty())
      value +=
          cascade::seen_from(reach_.data() + std::size_t(q) * dirs_.size(), probe, lights,
                             [&](const cascade::PointLight& pl) { return view.clear(*this, pl); });
    return true;
  };
  return tent(0, p, 2, serve, out);
}

// The free voxel nearest p in front of its surface (within 2 voxels each way), whose centre
// probes must see; p itself lies in its surface's opaque voxels (near an edge, in the other
// surface's too, so a step along the normal alone may not leave them).
Vec3 RadianceField::free_point_near(Vec3 p, Vec3 n) const {
  const Voxels& v = *voxels_;
  Vec3 free_point = p + n * (2 * v.size);
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
  return free_point;
}

template <class Value, class T>
bool RadianceField::surface_read(int i, Vec3 p, Vec3 n, const RayScene* rays,
                                 std::vector<cascade::PointLight>& lights, Value&& probe_value,
                                 T& out) const {
  const Voxels& v = *voxels_;
  const Vec3 free_point = rays ? p + n * (2 * v.size) : free_point_near(p, n);
  UpperView view{p, n, free_point};
  auto serve = [&](std::uint64_t q, Vec3 probe, T& value) {
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
    if (!probe_value(q, value)) return false;
    if (!lights.empty())
      value +=
          cascade::seen_from(reach_.data() + std::size_t(q) * dirs_.size(), probe, lights,
                             [&](const cascade::PointLight& pl) { return view.clear(*this, pl); });
    return true;
  };
  // Where none of the 8 probes around p serves (they sit in the surface's own voxels, or behind
  // it), up to 4 probe spacings out.
  return tent(i, p, 4, serve, out);
}

bool RadianceField::mean_radiance(Vec3 p, Vec3 n, Rgb& out, const RayScene* rays) const {
  std::vector<cascade::PointLight>& lights = cascade::point_lights();
  lights_at(p, n, lights);
  return surface_read(
      0, p, n, rays, lights,
      [&](std::uint64_t q, Rgb& value) {
        return cascade::cosine_mean(dirs_, n, radiance_, q, value);
      },
      out);
}

namespace {

// A probe's U and T over a lobe, weighted together (the cone query's unmerged cascades); a light
// met at the point adds to U.
struct OwnThrough {
  Rgb own{}, through{};
  OwnThrough& operator+=(const OwnThrough& o) {
    own += o.own;
    through += o.through;
    return *this;
  }
  OwnThrough& operator+=(const Rgb& light) {
    own += light;
    return *this;
  }
  OwnThrough operator*(float w) const { return {own * w, through * w}; }
};

}  // namespace

bool RadianceField::lobe_radiance(Vec3 p, Vec3 n, Vec3 ns, Vec3 wo, float alpha, Rgb& out,
                                  const RayScene* rays) const {
  thread_local cascade::LobeCells cells;
  const Vec3 r = reflect(wo, ns);
  std::vector<cascade::PointLight>& lights = cascade::point_lights();
  Rgb acc{};
  bool merged = false;  // acc holds the merged cascade's answer
  for (int i = cascade::cone_cascade(levels_, alpha, cone_top()); i >= 0; --i) {
    const CascadePlan& c = plan_[std::size_t(i)];
    const float cell = cell_alpha(c.side), a = std::max(alpha, cell);
    const std::vector<Vec3>& dirs = i == 0 ? dirs_ : kept_[std::size_t(i)].dirs;
    // Cells wider than a quarter of the lobe weigh it over 4 x 4 points each (lobe_cells).
    cascade::lobe_cells(dirs, c.side, a, ns, wo, r, cascade::lobe_radius(i, c.side, a, cell), cells,
                        cell > alpha / cascade::kLobeCells ? cascade::kCellPoints : 1);
    if (cells.empty()) continue;
    lights.clear();
    if (i == 0) {
      // The lights met here, valued by the lobe itself over each light's cap (lobe_share), not
      // by cascade 0's coarse cells: with those a small light's highlight spread over 50-degree
      // cells (a metal sphere among small lights at roughness 0.3: 49.7% from the path tracer).
      lights_at(p, n, lights);
      const float mu = std::max(dot(ns, wo), 0.0f);
      for (cascade::PointLight& pl : lights) {
        const Vec3 to = pl.centre - p;
        const float d = length(to);
        pl.value =
            d > 0 ? pl.radiance * cascade::lobe_share(alpha, ns, wo, to * (1 / d), pl.omega, mu)
                  : Rgb{};
      }
    }
    if (!merged) {
      const RadianceStore& m = i == 0 ? radiance_ : kept_[std::size_t(i)].merged;
      Rgb got;
      if (!surface_read(
              i, p, n, rays, lights,
              [&](std::uint64_t q, Rgb& value) {
                const Rgb* probe = m.probe(q);
                return cascade::lobe_mean(
                    cells, [&](std::uint32_t d) { return cascade::holds_light(probe[d]); },
                    [&](std::uint32_t d) { return probe[d]; }, value);
              },
              got))
        continue;  // no light this way here: the merged cascade below stands in
      acc = got;
      merged = true;
      continue;
    }
    OwnThrough got;
    const Interval* intervals = kept_[std::size_t(i)].intervals.data();
    if (surface_read(
            i, p, n, rays, lights,
            [&](std::uint64_t q, OwnThrough& value) {
              const Interval* probe = intervals + std::size_t(q) * dirs.size();
              return cascade::lobe_mean(
                  cells, [&](std::uint32_t d) { return cascade::holds_light(probe[d].radiance); },
                  [&](std::uint32_t d) {
                    return OwnThrough{probe[d].radiance, probe[d].through};
                  },
                  value);
            },
            got))
      acc = got.own + got.through * acc;
  }
  out = acc;
  return merged;
}

std::uint64_t RadianceField::bytes() const {
  return RadianceStore::bytes(plan_[0].probes(), plan_[0].side) + sphere_.size() * sizeof(Rgb) +
         valid_.size() + (reach_.size() + reach1_.size()) * sizeof(float) +
         cone_bytes(plan_, cone_top());
}

// Cascade 0 claims no light in its maps: a point that reads them claims cascade 0's share itself,
// with the light's irradiance where the point is, and whether the probes around it see the light
// from their rays' reach. Interpolated between probes up to a spacing nearer the light, 1/d^2 and
// the 50-degree cells' cosines made a small light's pool too bright under it and too dim around
// (a radius-0.3 light over a wide floor, 96 x 72, whole image against the path tracer: 12.7% to
// 0.01% in view, 18.5% to 0.00% behind the camera; PERFORMANCE.md's 200 lights at 320 x 180: 45%
// to 7.3%).
void RadianceField::lights_at(Vec3 p, Vec3 n, std::vector<cascade::PointLight>& out) const {
  out.clear();
  if (lights_.empty()) return;
  const float edge = plan_.size() > 1 ? lights_.claim_from() * plan_[1].t_start : 0;
  lights_.at_point(p, n, edge, plan_[0].side, dirs_, out);
  for (cascade::PointLight& pl : out) pl.end = plan_.size() > 1 ? plan_[0].t_end : kInfinity;
}

// Past cascade 0's rays, cascade 1's probes around p that `from` (a free point in front of p)
// sees ask their own rays towards the light, as a probe's claim asks its upper probes (cascade
// 0's stop is the nearest of its continuation's children, 50 degrees apart: a light low over a
// floor was hidden past two floor heights). Found once per point, where first asked.
float RadianceField::UpperView::clear(const RadianceField& f, const cascade::PointLight& pl) {
  const Voxels& v = *f.voxels_;
  const CascadePlan& c1 = f.plan_[1];
  if (!ready) {
    ready = true;
    const bool horizon = dot(n, n) > 0;
    around = corners(v, c1, p);
    up = cascade::uppers_of(around, c1.t_start,
                            [&](std::size_t j) { return position_of(v, c1, around.index[j]); });
    float kept = 0;
    for (std::size_t j = 0; j < 8; ++j) {
      if (!(up.w[j] > 0)) continue;
      const Vec3 to = up.p[j] - from;
      const float dist = length(to);
      if (!probe_free(v, c1, around.index[j]) || (horizon && dot(up.p[j] - p, n) < 0) ||
          (dist > 0 && march(v, from, to * (1 / dist), 0, dist).blocked))
        up.w[j] = 0;
      kept += up.w[j];
    }
    none = !(kept > 0);
  }
  if (none) return 0;  // none to ask: the cells alone say
  const std::size_t cells = std::size_t(c1.side) * std::size_t(c1.side);
  return cascade::upper_clear(up, c1.side, {pl.centre, pl.radius, {}},
                              [&](std::size_t j, std::size_t k) {
                                return f.reach1_[std::size_t(around.index[j]) * cells + k];
                              });
}

namespace {

// A level serves a point from a probe spacing inside its cut faces, blended into the next level
// over 8 voxels: no seam where the voxels and probes double.
constexpr float kBlendBand = 8;

}  // namespace

bool LevelFields::mean_radiance(Vec3 p, Vec3 n, Rgb& out, const RayScene* rays) const {
  return map->blend(
      p, float(fields[0].cascades()[0].spacing), kBlendBand,
      [&](std::size_t l, Rgb& v) { return fields[l].mean_radiance(p, n, v, rays); }, out);
}

bool LevelFields::lobe_radiance(Vec3 p, Vec3 n, Vec3 ns, Vec3 wo, float alpha, Rgb& out,
                                const RayScene* rays) const {
  return map->blend(
      p, float(fields[0].cascades()[0].spacing), kBlendBand,
      [&](std::size_t l, Rgb& v) { return fields[l].lobe_radiance(p, n, ns, wo, alpha, v, rays); },
      out);
}

bool LevelFields::sphere_radiance(Vec3 p, Rgb& out) const {
  return map->blend(
      p, float(fields[0].cascades()[0].spacing), kBlendBand,
      [&](std::size_t l, Rgb& v) { return fields[l].sphere_radiance(p, v); }, out);
}

std::uint64_t LevelFields::rays() const {
  std::uint64_t n = 0;
  for (const RadianceField& f : fields) n += f.rays();
  return n;
}

namespace {

// The light leaving surface voxel k towards one side: albedo times the mean radiance about the
// normal of its free faces on that side (`drop`: the thin axis's face on the other side), plus
// the sun's E cos / pi where a shadow ray from one voxel out along that normal reaches it.
Rgb reflected(const Voxels& v, const RadianceField& field, const SunLight* sun, std::size_t k,
              Vec3 centre, const bool (&open)[3][2], int drop_axis, int drop_side, Vec3& normal,
              std::uint64_t& rays) {
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
  if (field.mean_radiance(centre, normal, mean)) out += v.albedo[k] * mean;
  if (sun) out += sun->reflected(centre + n * v.size, normal, v.albedo[k], rays);
  return out;
}

}  // namespace

std::uint64_t add_bounce(Voxels& v, const RadianceField& field, const std::vector<Rgb>& base,
                         const SunLight* sun, std::vector<Vec3>* normals) {
  // Written aside: the field marches these voxels meanwhile.
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
          next[k] += v.extinction[k] * v.albedo[k] * in_scattered(field, sun, centre, rays);
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
        Vec3 normal;
        if (thin_axis < 0) {
          next[k] += reflected(v, field, sun, k, centre, open, -1, -1, normal, rays);
          minus[k] = next[k];
        } else {
          // Both sides: towards + (the - face dropped) and towards -.
          Vec3 other;
          next[k] += reflected(v, field, sun, k, centre, open, thin_axis, 0, normal, rays);
          minus[k] += reflected(v, field, sun, k, centre, open, thin_axis, 1, other, rays);
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

}  // namespace penumbra::spaceland::grid
