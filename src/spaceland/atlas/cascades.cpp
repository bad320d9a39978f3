#include "spaceland/atlas/cascades.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "spaceland/brdf_albedo.hpp"
#include "spaceland/cascade/cone.hpp"
#include "spaceland/cascade/levels.hpp"
#include "spaceland/cascade/radiance.hpp"
#include "spaceland/cascade/sphere_lights.hpp"
#include "spaceland/cascade/store.hpp"
#include "spaceland/color.hpp"
#include "spaceland/sky.hpp"
#include "spaceland/sun.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland::atlas {
namespace {

// One cascade's probes: per chart a grid of `spacing`-texel cells over its rectangle, each
// cell's probe on the covered texel of that chart nearest the cell's centre (none where the
// cell holds no covered texel).
struct Probe {
  Vec3 position, normal;
  Vec3 local;  // the normal in its chart's direction frame (direction_frame), where its maps lie
  float x = 0, y = 0;  // its texel's centre in the atlas
  bool valid = false;
  std::uint32_t chart = 0;
};

struct Grid {
  int spacing = 1;
  std::vector<std::uint64_t> base;  // per chart: its first probe
  std::vector<int> nx, ny;          // per chart: its grid
  std::vector<Probe> probes;
};

bool planar(const Chart& c) {
  return c.kind == ChartKind::disk || (c.kind == ChartKind::mesh && !c.from_lightmap);
}

Grid place(const Atlas& a, const std::vector<Texel>& texels, int spacing) {
  Grid g;
  g.spacing = spacing;
  g.base.resize(a.charts.size());
  g.nx.resize(a.charts.size());
  g.ny.resize(a.charts.size());
  for (std::size_t c = 0; c < a.charts.size(); ++c) {
    const Chart& ch = a.charts[c];
    g.base[c] = g.probes.size();
    g.nx[c] = (ch.width + spacing - 1) / spacing;
    g.ny[c] = (ch.height + spacing - 1) / spacing;
    g.probes.resize(g.probes.size() + std::size_t(g.nx[c]) * std::size_t(g.ny[c]));
  }
  // A texel the chart only touches holds the chart's nearest point, on its rim: at a room's
  // corner that point lies on the next wall's plane too, and rays from it along that wall meet
  // its far side at t ~ 0. Such a probe starts a hundredth of the way towards a neighbour whose
  // centre the chart holds.
  auto inside = [&](int x, int y, int c, Vec3 p) {
    for (int r = 1; r <= 2; ++r)
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx) {
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= a.width || ny >= a.height) continue;
          const Texel& t = texels[std::size_t(ny) * std::size_t(a.width) + std::size_t(nx)];
          if (t.chart == c && t.claims > 0) return p + (t.position - p) * 0.01f;
        }
    return p;
  };
  parallel_for(int(a.charts.size()), [&](int c) {
    const Chart& ch = a.charts[std::size_t(c)];
    const DirectionFrame frame = direction_frame(ch);
    for (int b = 0; b < g.ny[std::size_t(c)]; ++b)
      for (int i = 0; i < g.nx[std::size_t(c)]; ++i) {
        const float cx = float(ch.x) + (float(i) + 0.5f) * float(spacing);
        const float cy = float(ch.y) + (float(b) + 0.5f) * float(spacing);
        Probe& p = g.probes[g.base[std::size_t(c)] +
                            std::size_t(b) * std::size_t(g.nx[std::size_t(c)]) + std::size_t(i)];
        float best = 3e38f;
        for (int y = ch.y + b * spacing; y < std::min(ch.y + (b + 1) * spacing, ch.y + ch.height);
             ++y)
          for (int x = ch.x + i * spacing; x < std::min(ch.x + (i + 1) * spacing, ch.x + ch.width);
               ++x) {
            const Texel& t = texels[std::size_t(y) * std::size_t(a.width) + std::size_t(x)];
            if (t.chart != c) continue;
            const float dx = float(x) + 0.5f - cx, dy = float(y) + 0.5f - cy;
            if (dx * dx + dy * dy >= best) continue;
            best = dx * dx + dy * dy;
            p = {t.claims > 0 ? t.position : inside(x, y, c, t.position),
                 t.normal,
                 frame.to_local(t.normal),
                 float(x) + 0.5f,
                 float(y) + 0.5f,
                 true,
                 std::uint32_t(c)};
          }
        // An even spacing puts the cell's centre on a texel corner, half a texel from the nearest
        // texel's centre: where the four texels around it are the chart's (a flat one), the probe
        // stands on that corner, where the bilinear weights of the merge and the gather take it
        // (on the nearest texel, a small light's pool was drawn half a texel off: a sphere light
        // over a floor 2.9% from the path tracer, 0.5% centred; the two rooms 0.303 -> 0.183, four
        // cubes 0.087 -> 0.052, but the Cornell box 0.092 -> 0.112, a band under its ceiling).
        if (spacing % 2 == 0 && p.valid && planar(ch)) {
          const int x0 = int(cx) - 1, y0 = int(cy) - 1;
          Vec3 sum{};
          int n = 0;
          for (int y = y0; y <= y0 + 1; ++y)
            for (int x = x0; x <= x0 + 1; ++x) {
              if (x < ch.x || y < ch.y || x >= ch.x + ch.width || y >= ch.y + ch.height) continue;
              const Texel& t = texels[std::size_t(y) * std::size_t(a.width) + std::size_t(x)];
              if (t.chart != c || t.claims == 0 || dot(t.normal, p.normal) < 0.9999f) continue;
              sum += t.position;
              ++n;
            }
          // Their mean: on the surface, where a chart's plane may lie a little off it (the
          // Cornell box's measured walls). Not at a chart's rim: by a room's corner, the point
          // there lies on the next wall's plane too, and its rays along that wall meet it at once.
          if (n == 4) {
            p.position = sum * 0.25f;
            p.x = cx;
            p.y = cy;
          }
        }
      }
  });
  return g;
}

// f(bit, q, w) for the four probes of `upper` around atlas point (x, y) of chart c (clamped to
// its grid): corner (i, j) as bit j * 2 + i, its probe's index q and its bilinear weight w.
template <class F>
void for_each_corner(const Atlas& a, const Grid& upper, std::size_t c, float x, float y, F&& f) {
  const Chart& ch = a.charts[c];
  const float s = float(upper.spacing);
  const float gx = (x - float(ch.x)) / s - 0.5f, gy = (y - float(ch.y)) / s - 0.5f;
  const int x0 = int(std::floor(gx)), y0 = int(std::floor(gy));
  const float fx = gx - float(x0), fy = gy - float(y0);
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const int px = std::clamp(x0 + i, 0, upper.nx[c] - 1);
      const int py = std::clamp(y0 + j, 0, upper.ny[c] - 1);
      f(unsigned(j * 2 + i),
        upper.base[c] + std::uint64_t(py) * std::uint64_t(upper.nx[c]) + std::uint64_t(px),
        (i ? fx : 1 - fx) * (j ? fy : 1 - fy));
    }
}

// The (up to) four probes of `upper` around atlas point (x, y) of chart c, bilinearly weighted
// (the valid ones of those `seen` holds, bit j * 2 + i for corner (i, j); merge_children
// normalises over those with light).
cascade::Corners corners(const Atlas& a, const Grid& upper, std::size_t c, float x, float y,
                         unsigned seen = 0xF) {
  cascade::Corners k;
  for_each_corner(a, upper, c, x, y, [&](unsigned bit, std::uint64_t q, float w) {
    if (!(seen >> bit & 1u) || w <= 0 || !upper.probes[q].valid) return;
    k.index[std::size_t(k.n)] = q;
    k.w[std::size_t(k.n)] = w;
    ++k.n;
  });
  return k;
}

// A sphere light is claimed as a footprint (cascade::SphereLights) by the probes of a flat chart
// while it covers under kFootprintCells cells of the cascade whose interval holds its distance
// from the chart (cascade::Region: one judgement for all the chart's probes) and the sine of its
// half-angle from there is under kFootprintSine. The claim's irradiance is exact (the gather's
// share is scaled to Lambert's) but its visibility is the footprint's cells': past 64 cells the
// light is traced, whose cells resolve a penumbra (the methods ladder's penumbra under a plate
// stalled at 7.7% with every light claimed, 2.5% so). The sine keeps a light's own surface and the
// points touching it from claiming it (2 pi is 32 of cascade 0's 64 cells: a lamp was seen 8x too
// bright). Quads, disks and boxes are traced: claimed as SPWI does, the scene family's panels
// behind the camera went from 13-29% to 17-48%, and the two rooms from 0.183 to 0.416. A curved
// chart traces them too: its upper probes face other ways than the texels that merge them (claims
// at cascade 0 alone, the upper probes passing the lights that the texels traced, darkened a bunny
// by its lamp).
constexpr double kFootprintCells = 64;
constexpr double kFootprintSine = 0.5;

// How far off a flat chart the rays that look for walls run, in its texels: under any wall
// that stands on it, over the surface's own rounding.
constexpr float kWallLift = 1.0f / 20;

// Whether a wall stands across a flat chart of normal n between two points lifted off it: a
// surface met on the way whose plane meets the chart's at more than 45 degrees (a room's wall, a
// box's side). The underside of a sphere or a ramp resting on the chart meets it at a grazing
// angle and is no wall: the light under it falls to the contact continuously, and its texels are
// read as any others (the sky over a black sphere lost its contact shadow: 0.016 -> 0.050).
bool wall_between(const RayScene& rays, Vec3 from, Vec3 to, Vec3 n) {
  Ray r{from, to - from, 0, 1};
  for (int k = 0; k < 4; ++k) {
    Hit h;
    if (!rays.intersect(r, h)) return false;
    if (std::abs(dot(h.geometric_normal, n)) < 0.7071f) return true;
    r.tmin = std::nextafter(h.t, 2.0f);
  }
  return false;
}

// Per chart, whether it is flat: planar with every covered texel's normal its plane's. Walls are
// looked for on flat charts only: on a curved one (a mesh chart spans up to 45 degrees of normals)
// a chord between two of its points runs under the surface and would meet the chart itself.
std::vector<std::uint8_t> flat_charts(const Atlas& a, const std::vector<Texel>& texels) {
  std::vector<std::uint8_t> flat(a.charts.size());
  for (std::size_t c = 0; c < a.charts.size(); ++c) flat[c] = planar(a.charts[c]);
  for (const Texel& t : texels)
    if (t.chart >= 0 && std::abs(dot(t.normal, a.charts[std::size_t(t.chart)].n)) < 0.9999f)
      flat[std::size_t(t.chart)] = 0;
  return flat;
}

// Per probe of `lower`, which of its four corners in `upper` (corners()) it sees along its
// surface: bits 0-3 on the side its normal points to, 4-7 on the other. A probe by a room's wall
// on a floor that runs on under it has corners past the wall, whose rays see outdoors: merged
// in, they would bring the sky into the room along its walls (every direction in which the
// probe's own short interval meets nothing). A wall between them hides a corner on both sides;
// a probe of a chart that is not flat (flat_charts) sees all of them.
std::vector<std::uint8_t> seen_corners(const Atlas& a, const RayScene& rays,
                                       const std::vector<std::uint8_t>& flat, const Grid& lower,
                                       const Grid& upper) {
  std::vector<std::uint8_t> seen(lower.probes.size(), 0xFF);
  parallel_for(int(lower.probes.size() + 255) / 256, [&](int block) {
    const std::size_t stop = std::min(lower.probes.size(), std::size_t(block + 1) * 256);
    for (std::size_t q = std::size_t(block) * 256; q < stop; ++q) {
      const Probe& p = lower.probes[q];
      const Chart& c = a.charts[p.chart];
      if (!p.valid || !flat[p.chart]) continue;
      std::uint8_t bits = 0;
      for_each_corner(a, upper, p.chart, p.x, p.y, [&](unsigned bit, std::uint64_t uq, float) {
        const Probe& u = upper.probes[uq];
        if (!u.valid) return;
        for (int side = 0; side < 2; ++side) {
          const Vec3 lift = p.normal * ((side ? -kWallLift : kWallLift) * c.texel_size);
          const Vec3 from = p.position + lift;
          if (!wall_between(rays, from, u.position + lift, c.n))
            bits = std::uint8_t(bits | 1u << (bit + 4 * unsigned(side)));
        }
      });
      seen[q] = bits;
    }
  });
  return seen;
}

// f(k, q) for every covered texel k of the atlas and its cascade-0 probe q (a probe per texel),
// a chart per task.
template <class F>
void for_each_texel_probe(const Atlas& a, const Grid& g0, F&& f) {
  parallel_for(int(a.charts.size()), [&](int c) {
    const Chart& ch = a.charts[std::size_t(c)];
    for (int y = ch.y; y < ch.y + ch.height; ++y)
      for (int x = ch.x; x < ch.x + ch.width; ++x) {
        const std::uint64_t q = g0.base[std::size_t(c)] +
                                std::uint64_t(y - ch.y) * std::uint64_t(g0.nx[std::size_t(c)]) +
                                std::uint64_t(x - ch.x);
        if (g0.probes[q].valid) f(std::size_t(y) * std::size_t(a.width) + std::size_t(x), q);
      }
  });
}

// Whether direction d leaves a surface of normal n on the side whose cosine is `cos` (a
// direction in the plane counts as the front's, where spawn() starts it).
bool same_side(Vec3 n, Vec3 d, float cos) {
  return (dot(n, d) >= 0) == (cos >= 0);
}

// A lower probe's ray that met nothing in its interval, merged (seed 001 eq. 13-14) with the
// upper probes' children of its cell on the side of the surface it left from (`cos`, its
// cosine): a cell across the plane of a thin wall has children on both sides, and those on the
// far side were traced from there (outdoors, for a room's wall). False where none holds light.
bool merge_side(const cascade::RadianceStore& above, const Grid& upper, const cascade::Corners& k,
                const std::vector<Vec3>& dirs_above, Vec3 n, float cos, int u, int v, Rgb& out) {
  return cascade::merge_children(above, k, u, v, 2, out, [&](std::uint64_t q, std::size_t c) {
    return same_side(n, dirs_above[c], cos) && same_side(upper.probes[q].local, dirs_above[c], cos);
  });
}

// A small light's share that a cascade-0 probe claimed in one cell of its map (index probe * cells
// + cell): fine_gather reads a cell whose ray went on through the merge from the cascade above's
// children, and adds it back.
struct Claim {
  std::uint64_t at = 0;
  Rgb light;
};

// Every covered texel's irradiance on each side from cascade 0 (store, side0 x side0 cells) at
// cascade 1's directions (dirs1, 2 side0 on a side): a cell whose ray was merged gives each of its
// 2x2 children the bilinear mean of the upper probes' child (those with light; the cell's own
// value where none has, plus the small lights cascade 0 claimed in it, `claimed`, sorted), a cell
// whose ray met a surface its value, each weighted by its own cosine.
void fine_gather(const Atlas& a, const Grid& g0, const Grid& g1,
                 const std::vector<std::uint8_t>& seen, const std::vector<Vec3>& dirs0,
                 const std::vector<Vec3>& dirs1, int side0, const cascade::RadianceStore& store,
                 const cascade::RadianceStore& above, const std::vector<std::uint8_t>& merged,
                 const std::vector<Claim>& claimed, std::vector<Rgb>& front,
                 std::vector<Rgb>& back) {
  const std::size_t nd0 = std::size_t(side0) * std::size_t(side0);
  const std::size_t side1 = 2 * std::size_t(side0);
  for_each_texel_probe(a, g0, [&](std::size_t t, std::uint64_t q) {
    const Probe& p = g0.probes[q];
    auto claim = std::lower_bound(claimed.begin(), claimed.end(), q * nd0,
                                  [](const Claim& c, std::uint64_t at) { return c.at < at; });
    const cascade::Corners kf = corners(a, g1, p.chart, p.x, p.y, seen[q] & 0xFu);
    const cascade::Corners kb = corners(a, g1, p.chart, p.x, p.y, unsigned(seen[q]) >> 4);
    const Rgb* values = store.probe(q);
    Rgb f{}, b{};
    float wf = 0, wb = 0;
    for (int v = 0; v < side0; ++v)
      for (int u = 0; u < side0; ++u) {
        const std::size_t d = std::size_t(v) * std::size_t(side0) + std::size_t(u);
        const Rgb& cell = values[d];
        // The side of the surface the cell's own ray left from: its value is light on that side
        // only (a cell across the surface's plane, on a thin wall, holds no light for the other).
        const float cell_cos = dot(p.local, dirs0[d]);
        Rgb extra{};
        if (claim != claimed.end() && claim->at == q * nd0 + d) extra = (claim++)->light;
        for (int dv = 0; dv < 2; ++dv)
          for (int du = 0; du < 2; ++du) {
            const std::size_t child = (2 * std::size_t(v) + std::size_t(dv)) * side1 +
                                      2 * std::size_t(u) + std::size_t(du);
            const float cos_t = dot(p.local, dirs1[child]);
            if (cos_t == 0) continue;
            Rgb l = (cos_t > 0) == (cell_cos >= 0) ? cell : cascade::kNoLight;
            const cascade::Corners& k = cos_t > 0 ? kf : kb;
            if (merged[q * nd0 + d]) {
              Rgb sum{};
              float w = 0;
              for (int j = 0; j < k.n; ++j) {
                const Rgb& r = above.probe(k.index[std::size_t(j)])[child];
                if (!cascade::holds_light(r) ||
                    !same_side(g1.probes[k.index[std::size_t(j)]].local, dirs1[child], cos_t))
                  continue;
                sum += r * k.w[std::size_t(j)];
                w += k.w[std::size_t(j)];
              }
              if (w > 0) l = sum * (1 / w) + extra;
            }
            if (!cascade::holds_light(l)) continue;
            if (cos_t > 0) {
              f += l * cos_t;
              wf += cos_t;
            } else if (cos_t < 0) {
              b += l * -cos_t;
              wb -= cos_t;
            }
          }
      }
    front[t] = wf > 0 ? f * float(kPi / wf) : Rgb{};
    back[t] = wb > 0 ? b * float(kPi / wb) : Rgb{};
  });
}

}  // namespace

std::uint64_t bake_bytes(std::uint64_t texels, int side0) {
  // Cascade i has about texels / 4^i probes of 4^i side0^2 directions: each store about cascade
  // 0's (a chart's partial cells round up: 2x at most), two live at once, and with small lights
  // where each of their rays stopped.
  const std::uint64_t rays = texels * std::uint64_t(side0) * std::uint64_t(side0);
  return 2 * 2 * (cascade::RadianceStore::bytes(texels, side0) + rays * sizeof(float)) +
         texels * (sizeof(Texel) + 4 * sizeof(Rgb) + 2 * sizeof(Probe));
}

namespace {

// Calls f(k, w) for each of the (up to) four texels of the atlas around uv, with its bilinear
// weight.
template <class F>
void for_each_tap(const Atlas& a, Uv uv, F&& f) {
  const float gx = uv.x - 0.5f, gy = uv.y - 0.5f;
  const int x0 = int(std::floor(gx)), y0 = int(std::floor(gy));
  const float fx = gx - float(x0), fy = gy - float(y0);
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const int x = x0 + i, y = y0 + j;
      if (x < 0 || y < 0 || x >= a.width || y >= a.height) continue;
      f(std::size_t(y) * std::size_t(a.width) + std::size_t(x),
        (i ? fx : 1 - fx) * (j ? fy : 1 - fy));
    }
}

}  // namespace

Rgb Baked::light(std::size_t k, bool f, bool with_sun) const {
  Rgb e = f ? front[k] : back[k];
  if (with_sun) e += f ? sun_front[k] : sun_back[k];
  return e;
}

template <class Value, class Keep>
Rgb Baked::within(std::uint32_t chart, Uv uv, bool front, float& weight, Value&& value,
                  Keep&& keep) const {
  Rgb sum{};
  weight = 0;
  for_each_tap(atlas, uv, [&](std::size_t k, float w) {
    if (texels[k].chart != int(chart) || !keep(k)) return;
    sum += value(k, front) * w;
    weight += w;
  });
  return sum;
}

namespace {

// The centre of atlas texel (x, y) on planar chart c's plane, extended past its rim.
Vec3 plane_point(const Chart& c, int x, int y) {
  const float s = float(x - c.shift_x) + 0.5f, t = float(y - c.shift_y) + 0.5f;
  return c.origin + (c.u * s + c.v * t) * c.texel_size;
}

}  // namespace

template <class Value>
Rgb Baked::read_at(const Scene& scene, const RayScene& rays, const Hit& hit, Vec3 towards,
                   Value&& value) const {
  std::uint32_t chart = 0;
  const Uv uv = atlas.locate(scene, hit, chart);
  // The side is the hit's, read from every texel: a chart's normals (and a linked chart's) face
  // one way, within 45 degrees on a mesh and outwards on a sphere, so a texel's front is the
  // hit's. Deciding it from each texel's own normal failed where few texels span a curved
  // surface: a small lamp's sphere of 2x2 texels, whose normals lie across the viewer's line,
  // read some texels' insides and shone at up to 1.7x its emission.
  const bool front = dot(hit.geometric_normal, towards) >= 0;
  // By a wall: only the texels whose centre this point sees along the surface (a floor's texel
  // past a room's wall sees the sun; one under it, the wall's inside).
  bool near = false;
  if (!walled.empty())
    for_each_tap(atlas, uv, [&](std::size_t k, float) {
      near = near || (texels[k].chart == int(chart) && walled[k]);
    });
  const Chart& c = atlas.charts[chart];
  const Vec3 lift =
      (front ? hit.geometric_normal : -hit.geometric_normal) * (kWallLift * c.texel_size);
  const Vec3 from = hit.position + lift;
  auto sees = [&](Vec3 centre) { return !wall_between(rays, from, centre + lift, c.n); };
  auto keep = [&](std::size_t k) { return !near || sees(texels[k].position); };
  float weight = 0;
  Rgb sum = within(chart, uv, front, weight, value, keep);
  // Past the rim: the light where the surface goes on, read in its own chart.
  if (!seams.empty())
    for_each_tap(atlas, uv, [&](std::size_t k, float w) {
      if (texels[k].chart >= 0 || !(w > 0)) return;
      const auto link =
          std::lower_bound(seams.begin(), seams.end(), std::uint32_t(k),
                           [](const SeamLink& l, std::uint32_t key) { return l.texel < key; });
      if (link == seams.end() || link->texel != k || link->from != chart) return;
      // (A walled tap lies on a flat chart: its plane runs on there.)
      if (near && !sees(plane_point(c, int(k % std::size_t(atlas.width)),
                                    int(k / std::size_t(atlas.width)))))
        return;
      float there = 0;
      const Rgb e =
          within(link->chart, link->uv, front, there, value, [](std::size_t) { return true; });
      if (there > 0) {
        sum += e * (w / there);
        weight += w;
      }
    });
  if (weight > 0) return sum * (1 / weight);
  // None of the four counts (a point on a chart's rim, or walled off): its chart's nearest
  // covered texel it sees, within the 2.5 texels locate() keeps to; the nearest one where it
  // sees none.
  const int x0 = int(std::floor(uv.x - 0.5f)), y0 = int(std::floor(uv.y - 0.5f));
  float best = 3e38f, best_seen = 3e38f;
  Rgb nearest{}, nearest_seen{};
  for (int y = y0 - 2; y <= y0 + 3; ++y)
    for (int x = x0 - 2; x <= x0 + 3; ++x) {
      if (x < 0 || y < 0 || x >= atlas.width || y >= atlas.height) continue;
      const std::size_t k = std::size_t(y) * std::size_t(atlas.width) + std::size_t(x);
      if (texels[k].chart != int(chart)) continue;
      const float dx = float(x) + 0.5f - uv.x, dy = float(y) + 0.5f - uv.y;
      const float d2 = dx * dx + dy * dy;
      if (d2 < best) {
        best = d2;
        nearest = value(k, front);
      }
      if (near && d2 < best_seen && sees(texels[k].position)) {
        best_seen = d2;
        nearest_seen = value(k, front);
      }
    }
  return best_seen < 3e38f ? nearest_seen : nearest;
}

Rgb Baked::irradiance_at(const Scene& scene, const RayScene& rays, const Hit& hit, Vec3 towards,
                         bool with_sun) const {
  return read_at(scene, rays, hit, towards,
                 [&](std::size_t k, bool front) { return light(k, front, with_sun); });
}

Rgb Baked::lobe_at(const Scene& scene, const RayScene& rays, const Hit& hit, Vec3 wo, Vec3 n,
                   float alpha) const {
  if (side0 <= 0) return {};
  thread_local std::vector<Vec3> dirs;
  thread_local int dirs_side = 0;
  if (dirs_side != side0) {
    dirs = octahedral::map_directions(side0);
    dirs_side = side0;
  }
  const float cell = cell_alpha(side0), a = std::max(alpha, cell);
  const int sub = cell > alpha / cascade::kLobeCells ? cascade::kCellPoints : 1;
  const std::size_t nd = dirs.size();
  // The lobe's cells in each chart's frame the taps read (the hit's, a seam's other chart).
  struct Charted {
    int chart = -1;
    cascade::LobeCells cells;
  };
  thread_local std::array<Charted, 2> made;
  for (Charted& c : made) c.chart = -1;
  const Vec3 r = reflect(wo, n);
  auto cells_of = [&](int chart) -> const cascade::LobeCells& {
    for (Charted& c : made)
      if (c.chart == chart) return c.cells;
    Charted& c = made[made[0].chart < 0 ? 0 : 1];
    const DirectionFrame f = direction_frame(atlas.charts[std::size_t(chart)]);
    c.chart = chart;
    cascade::lobe_cells(dirs, side0, a, f.to_local(n), f.to_local(wo), f.to_local(r), side0,
                        c.cells, sub);
    return c.cells;
  };
  return read_at(scene, rays, hit, wo, [&](std::size_t k, bool) {
    const Rgb* probe = radiance.data() + k * nd;
    Rgb mean{};
    cascade::lobe_mean(
        cells_of(texels[k].chart), [](std::uint32_t) { return true; },
        [&](std::uint32_t d) { return probe[d]; }, mean);
    return mean;
  });
}

void link_seams(const Scene& scene, const RayScene& rays, Baked& b) {
  const Atlas& a = b.atlas;
  const float cos_max = std::cos(45.0f * float(kPi) / 180);
  std::vector<std::vector<Baked::SeamLink>> per_chart(a.charts.size());
  parallel_for(int(a.charts.size()), [&](int id) {
    const Chart& c = a.charts[std::size_t(id)];
    if (!planar(c)) return;
    for (int y = std::max(0, c.y - 1); y < std::min(a.height, c.y + c.height + 1); ++y)
      for (int x = std::max(0, c.x - 1); x < std::min(a.width, c.x + c.width + 1); ++x) {
        const std::size_t k = std::size_t(y) * std::size_t(a.width) + std::size_t(x);
        if (b.texels[k].chart >= 0) continue;
        // The chart's covered texel beside it (the first of the 8): its normal, its side.
        int rim = -1;
        for (int dy = -1; dy <= 1 && rim < 0; ++dy)
          for (int dx = -1; dx <= 1 && rim < 0; ++dx) {
            const int u = x + dx, v = y + dy;
            if ((dx || dy) && u >= 0 && v >= 0 && u < a.width && v < a.height &&
                b.texels[std::size_t(v) * std::size_t(a.width) + std::size_t(u)].chart == id)
              rim = v * a.width + u;
          }
        if (rim < 0) continue;
        const Vec3 n = b.texels[std::size_t(rim)].normal;
        // The empty texel's centre on the chart's plane, extended past its rim.
        const Vec3 q = plane_point(c, x, y);
        const float reach = 1.5f * c.texel_size;
        Hit h;
        if (!rays.intersect(Ray{q + n * reach, -n, 0, 2 * reach}, h)) continue;
        if (dot(h.geometric_normal, n) < cos_max) continue;  // a crease, or a back face
        std::uint32_t chart = 0;
        const Uv uv = a.locate(scene, h, chart);
        if (int(chart) == id) continue;
        per_chart[std::size_t(id)].push_back({std::uint32_t(k), std::uint32_t(id), chart, uv});
      }
  });
  b.seams.clear();
  for (const auto& links : per_chart) b.seams.insert(b.seams.end(), links.begin(), links.end());
  std::sort(b.seams.begin(), b.seams.end(),
            [](const Baked::SeamLink& l, const Baked::SeamLink& r) { return l.texel < r.texel; });
}

namespace {

// mark_walls, the atlas's flat charts (flat_charts) given.
void mark_walls(const RayScene& rays, const std::vector<std::uint8_t>& flat, Baked& b) {
  const Atlas& a = b.atlas;
  b.walled.assign(b.texels.size(), 0);
  parallel_for(a.height, [&](int y) {
    for (int x = 0; x < a.width; ++x) {
      const std::size_t k = std::size_t(y) * std::size_t(a.width) + std::size_t(x);
      const Texel& t = b.texels[k];
      if (t.chart < 0) continue;
      const Chart& c = a.charts[std::size_t(t.chart)];
      if (!flat[std::size_t(t.chart)]) continue;
      for (const float side : {1.0f, -1.0f}) {
        const Vec3 lift = t.normal * (side * kWallLift * c.texel_size);
        const Vec3 from = t.position + lift;
        for (int dy = -1; dy <= 1 && !b.walled[k]; ++dy)
          for (int dx = -1; dx <= 1 && !b.walled[k]; ++dx)
            if ((dx || dy) && wall_between(rays, from, plane_point(c, x + dx, y + dy) + lift, c.n))
              b.walled[k] = 1;
      }
    }
  });
  if (std::find(b.walled.begin(), b.walled.end(), 1) == b.walled.end()) b.walled.clear();
}

}  // namespace

void mark_walls(const RayScene& rays, Baked& b) {
  mark_walls(rays, flat_charts(b.atlas, b.texels), b);
}

Expected<Baked> bake(const Scene& scene, const RayScene& rays, const Options& atlas_options,
                     const CascadeOptions& o, std::uint64_t max_bytes, BakeReport& report) {
  if (o.side0 < 2 || o.side0 > 64 || (o.side0 & (o.side0 - 1)) != 0)
    return Error{"surface cascades: side0 must be a power of two in [2, 64]"};
  if (!(o.t0 >= 0) || !std::isfinite(o.t0)) return Error{"surface cascades: t0 must be >= 0"};
  if (o.cascades < 0 || o.cascades > cascade::kMaxCascades)
    return Error{"surface cascades: cascades must be in [0, " +
                 std::to_string(cascade::kMaxCascades) + "]"};
  if (o.bounces < 1 || o.bounces > 64) return Error{"surface cascades: bounces must be in [1, 64]"};

  Stopwatch watch;
  Expected<Atlas> made = make_atlas(scene, atlas_options);
  if (!made) return made.error();
  Baked out;
  out.atlas = std::move(*made);
  out.texels = rasterise(scene, out.atlas);
  report.stages.push_back({"atlas", watch.ms()});
  watch.restart();

  const Atlas& a = out.atlas;
  cascade::Levels l;
  l.spacing0 = 1;
  l.side0 = o.side0;
  l.spacing_step = 1;
  l.side_step = 1;
  l.interval_step = 2;
  l.t0 = o.t0 > 0 ? o.t0 : 2 * a.texel_size;
  const Bounds b = scene_bounds(scene);
  const double reach = double(length(b.hi - b.lo));
  l.count = o.cascades > 0 ? o.cascades : cascade::count_to_reach(l, reach, cascade::kMaxCascades);
  report.cascades = l.count;
  report.t0 = l.t0;
  // Lights small for a probe's cells (cascade::SphereLights): passed through by its rays and
  // claimed as footprints over its cells instead, each refinement level's charts judging them by
  // their own intervals.
  std::vector<cascade::SphereLights> lights;
  if (o.small_lights) {
    int levels = 0;
    for (const Chart& c : a.charts) levels = std::max(levels, c.level + 1);
    for (int level = 0; level < levels; ++level) {
      cascade::Levels scaled = l;
      scaled.t0 = std::ldexp(l.t0, -level);
      lights.emplace_back(scene, scaled, false);
      lights.back().set_small(kFootprintCells, kFootprintSine);
    }
    if (lights.empty() || lights[0].empty()) lights.clear();
  }
  // Each chart's rectangle, where its probes judge a light's size from (cascade::Region).
  std::vector<cascade::Region> regions;
  for (const Chart& c : a.charts) {
    const float ts = c.texel_size;
    regions.push_back(
        {c.origin + (c.u * float(c.x - c.shift_x) + c.v * float(c.y - c.shift_y)) * ts,
         c.u * (float(c.width) * ts), c.v * (float(c.height) * ts)});
  }

  std::vector<Grid> grids;
  for (int i = 0; i < l.count; ++i) grids.push_back(place(a, out.texels, l.spacing(i)));
  // Two stores live at once: the cascade being traced and the one above it.
  std::uint64_t most = 0;
  report.probes.clear();
  report.store_bytes.clear();
  for (int i = 0; i < l.count; ++i) {
    std::uint64_t valid = 0;
    for (const Probe& p : grids[std::size_t(i)].probes) valid += p.valid ? 1 : 0;
    report.probes.push_back(valid);
    report.store_bytes.push_back(
        cascade::RadianceStore::bytes(grids[std::size_t(i)].probes.size(), l.side(i)));
  }
  for (int i = 0; i + 1 < l.count; ++i)
    most =
        std::max(most, report.store_bytes[std::size_t(i)] + report.store_bytes[std::size_t(i) + 1]);
  if (l.count == 1) most = report.store_bytes[0];
  // With small lights, where each ray of two cascades stopped.
  if (!lights.empty()) {
    std::uint64_t rays = 0;
    for (int i = 0; i < l.count; ++i)
      rays = std::max(rays, grids[std::size_t(i)].probes.size() * l.directions(i));
    most += 2 * rays * sizeof(float);
  }
  std::uint64_t probes = 0;
  for (const Grid& g : grids) probes += g.probes.size();
  report.memory_bytes =
      most + probes * sizeof(Probe) + out.texels.size() * (sizeof(Texel) + 4 * sizeof(Rgb));
  if (o.keep_radiance)
    report.memory_bytes += cascade::RadianceStore::bytes(out.texels.size(), o.side0);
  if (most > max_bytes)
    return Error{"surface cascades: two cascades' stores take " + std::to_string(most >> 20) +
                 " MiB, more than the " + std::to_string(max_bytes >> 20) +
                 " MiB allowed; use fewer texels (a larger texel size) or a smaller side0"};
  report.stages.push_back({"probes", watch.ms()});
  // The walls that merges and the lookups of light reflected past the first bounce keep to.
  watch.restart();
  const std::vector<std::uint8_t> flat = flat_charts(a, out.texels);
  mark_walls(rays, flat, out);
  std::vector<std::vector<std::uint8_t>> seen;
  for (int i = 0; i + 1 < l.count; ++i)
    seen.push_back(seen_corners(a, rays, flat, grids[std::size_t(i)], grids[std::size_t(i) + 1]));
  report.stages.push_back({"walls", watch.ms()});

  const Background bg(scene);
  const std::size_t n_texels = out.texels.size();
  out.front.assign(n_texels, Rgb{});
  out.back.assign(n_texels, Rgb{});
  out.sun_front.assign(n_texels, Rgb{});
  out.sun_back.assign(n_texels, Rgb{});
  {
    // The sun reaches one side of a texel at most: one shadow ray towards its centre from there.
    watch.restart();
    const SunLight sun(scene, rays);
    std::atomic<std::uint64_t> traced{0};
    if (sun.on())
      parallel_for(a.height, [&](int y) {
        std::uint64_t local = 0;
        for (int x = 0; x < a.width; ++x) {
          const std::size_t k = std::size_t(y) * std::size_t(a.width) + std::size_t(x);
          const Texel& t = out.texels[k];
          const float cos_s = dot(t.normal, sun.direction());
          if (t.chart < 0 || cos_s == 0) continue;
          const Rgb e =
              sun.at(rays.spawn(t.position, t.normal, sun.direction()), local) * std::abs(cos_s);
          (cos_s > 0 ? out.sun_front : out.sun_back)[k] = e;
        }
        traced.fetch_add(local, std::memory_order_relaxed);
      });
    report.rays += traced.load();
    report.stages.push_back({"sun", watch.ms()});
  }

  std::vector<std::vector<Vec3>> dirs;
  for (int i = 0; i < l.count; ++i) dirs.push_back(cascade::direction_map(l, i));
  std::vector<DirectionFrame> frames;
  for (const Chart& c : a.charts) frames.push_back(direction_frame(c));
  // Where each ray of the cascade above stopped (read) and of this one (written), probe-major as
  // the stores, its merged continuation included (infinity: at no surface).
  std::vector<float> upper_reach, lower_reach;

  for (int bounce = 1; bounce <= o.bounces; ++bounce) {
    watch.restart();
    // What a ray meets: the surface's emission and, past the first bounce, the light it reflects
    // from the last solve (on the side the ray sees).
    const Baked* last = bounce > 1 ? &out : nullptr;
    std::vector<Rgb> next_front(n_texels), next_back(n_texels);
    auto met = [&](Hit& h, Vec3 d) {
      Rgb radiance = emission_at(scene, h);
      if (last)
        // A glossy surface's view-dependent light, as the grid's voxels: the share of a uniform
        // light it reflects (hemispherical_albedo).
        radiance += hemispherical_albedo(brdf_at(scene, h)) *
                    last->irradiance_at(scene, rays, h, -d) * float(1 / kPi);
      return radiance;
    };
    std::atomic<std::uint64_t> traced{0};
    // Cascade 0's irradiance at cascade 1's directional resolution (fine_gather): where a cell's
    // ray went on through the merge, each of its 2x2 children keeps its own radiance and cosine.
    // A cell's cosine at its centre misweights light that fills part of it at a grazing angle
    // (the top of the Cornell box's back wall): from a camera inside the box, 0.269 -> 0.171.
    const bool fine = l.count > 1;
    // The gather the lights' shares are made exact for: cascade 0 read at cascade 1's directions.
    const cascade::GatherCells gather{&dirs[fine ? 1 : 0], l.side(fine ? 1 : 0)};
    const std::size_t nd0 = std::size_t(l.side(0)) * std::size_t(l.side(0));
    std::vector<std::uint8_t> merged0(fine ? grids[0].probes.size() * nd0 : 0);
    std::vector<Claim> claimed0;
    bool gathered = false;
    const cascade::RadianceStore c0 = cascade::top_down(
        l, [&](int i, const cascade::RadianceStore& above, cascade::RadianceStore& store) {
          const Grid& g = grids[std::size_t(i)];
          const int side = l.side(i);
          const std::vector<Vec3>& dir = dirs[std::size_t(i)];
          store.assign(g.probes.size(), side);
          const std::size_t nd = std::size_t(side) * std::size_t(side);
          const int side_above = l.top(i) ? 0 : l.side(i + 1);
          const std::size_t nd_above = std::size_t(side_above) * std::size_t(side_above);
          if (!lights.empty()) lower_reach.assign(g.probes.size() * nd, cascade::kInfinity);
          const float start_i = l.interval_start(i), end_i = l.interval_end(i);
          const float rest_end = cascade::kInfinity;
          // In blocks of probes, not per chart: a ground that is one chart would be one task.
          constexpr std::uint64_t kBlock = 64;
          const std::uint64_t blocks = (g.probes.size() + kBlock - 1) / kBlock;
          std::vector<std::vector<Claim>> claims(i == 0 && fine && !lights.empty() ? blocks : 0);
          parallel_for(int(blocks), [&](int block) {
            std::uint64_t local = 0;
            std::vector<Rgb> before;
            const std::uint64_t first = std::uint64_t(block) * kBlock;
            const std::uint64_t stop = std::min<std::uint64_t>(first + kBlock, g.probes.size());
            for (std::uint64_t q = first; q < stop; ++q) {
              const Probe& p = g.probes[q];
              if (!p.valid) continue;
              // Intervals in the chart's texels: a chart refined towards a light (Options::refine)
              // has its cascades' probes and intervals closer alike (the penumbra condition).
              const float scale = std::ldexp(1.0f, -a.charts[p.chart].level);
              const float start = scale * start_i, end = scale * end_i;
              const DirectionFrame& frame = frames[p.chart];
              const cascade::SphereLights* small =
                  lights.empty() || !flat[p.chart] ? nullptr
                                                   : &lights[std::size_t(a.charts[p.chart].level)];
              float* reach = small ? lower_reach.data() + q * nd : nullptr;
              // A ray that meets a small light goes on past it (its footprint brings its light).
              auto trace = [&](Ray r, Hit& h) {
                bool found = rays.intersect(r, h);
                for (int n = 0; small && found && n < 8; ++n) {
                  const float exit =
                      small->pass(scene, h, p.position, r.origin, r.direction, &regions[p.chart]);
                  if (exit < 0) break;
                  r.tmin = exit;
                  found = rays.intersect(r, h);
                }
                return found;
              };
              // The corners above it that it sees, on each side.
              const unsigned bits = l.top(i) ? 0 : seen[std::size_t(i)][q];
              const cascade::Corners kf =
                  l.top(i) ? cascade::Corners{}
                           : corners(a, grids[std::size_t(i) + 1], p.chart, p.x, p.y, bits & 0xF);
              const cascade::Corners kb =
                  l.top(i) ? cascade::Corners{}
                           : corners(a, grids[std::size_t(i) + 1], p.chart, p.x, p.y, bits >> 4);
              Rgb* values = store.probe(q);
              for (int v = 0; v < side; ++v)
                for (int u = 0; u < side; ++u) {
                  // The map lies in the chart's frame (no cell of a flat chart's across its
                  // plane); the ray in the world's.
                  const Vec3 dl = dir[std::size_t(v) * std::size_t(side) + std::size_t(u)];
                  const Vec3 d = frame.to_world(dl);
                  // Its side of the surface (a direction in the plane counts as the front's,
                  // where spawn() starts it).
                  const float cos = dot(dl, p.local);
                  const Vec3 from = rays.spawn(p.position, p.normal, d);
                  // One ray from the probe itself: a hit before the interval starts means its start
                  // lies behind a surface (past a room's wall, for a probe near a corner), so this
                  // direction holds no light here (kNoLight) and the merge below leaves it out,
                  // rather than letting the interval see through the wall.
                  Hit h;
                  Rgb value;
                  float stop = cascade::kInfinity;
                  const std::size_t k = std::size_t(v) * std::size_t(side) + std::size_t(u);
                  ++local;
                  if (trace(Ray{from, d, 0, l.top(i) ? rest_end : end}, h)) {
                    value = h.t < start ? cascade::kNoLight : met(h, d);
                    stop = h.t;
                  } else if (l.top(i)) {
                    value = bg.sky(d);
                  } else if (merge_side(above, grids[std::size_t(i) + 1], cos >= 0 ? kf : kb,
                                        dirs[std::size_t(i) + 1], p.local, cos, u, v, value)) {
                    if (fine && i == 0) merged0[q * nd0 + k] = 1;
                    if (small)
                      stop = cascade::merged_reach(cos >= 0 ? kf : kb, u, v, 2, upper_reach.data(),
                                                   side_above, end);
                  } else {
                    // No probe above holds light this way (or none of this chart is there): the
                    // rest of the ray, traced.
                    ++local;
                    const bool found = trace(Ray{from, d, end, rest_end}, h);
                    value = found ? met(h, d) : bg.sky(d);
                    if (found) stop = h.t;
                  }
                  values[k] = value;
                  if (reach) reach[k] = stop;
                }
              if (!small) continue;
              // Each side's small lights, over the cells whose rays reach them, the merge's
              // corners on that side claiming those farther off.
              if (!claims.empty()) before.assign(values, values + nd);
              for (int s = 0; s < 2; ++s) {
                const cascade::Corners& corner = s == 0 ? kf : kb;
                const bool merges = !l.top(i) && corner.n > 0;
                const cascade::Uppers up = cascade::uppers_of(corner, end, [&](std::size_t j) {
                  return grids[std::size_t(i) + 1].probes[std::size_t(corner.index[j])].position;
                });
                auto seen = [&](std::size_t cell, float dist) {
                  return reach[cell] >= start && reach[cell] >= dist ? 1.0f : 0.0f;
                };
                auto past = [&](const cascade::SphereLight& light) {
                  if (!merges) return 1.0f;
                  return cascade::upper_clear(
                      up, side_above, light,
                      [&](std::size_t j, std::size_t cell) {
                        return upper_reach[std::size_t(corner.index[j]) * nd_above + cell];
                      },
                      &frame);
                };
                small->add(p.position, s == 0 ? p.normal : -p.normal, start, end,
                           merges ? &up : nullptr, side, values, seen, past, &gather, &frame,
                           &regions[p.chart]);
              }
              if (!claims.empty())
                for (std::size_t k = 0; k < nd; ++k)
                  if (values[k].r != before[k].r || values[k].g != before[k].g ||
                      values[k].b != before[k].b)
                    claims[std::size_t(block)].push_back({q * nd + k, values[k] - before[k]});
            }
            traced.fetch_add(local, std::memory_order_relaxed);
          });
          for (const std::vector<Claim>& c : claims)
            claimed0.insert(claimed0.end(), c.begin(), c.end());
          std::swap(upper_reach, lower_reach);
          if (fine && i == 0) {
            fine_gather(a, g, grids[1], seen[0], dirs[0], dirs[1], side, store, above, merged0,
                        claimed0, next_front, next_back);
            gathered = true;
          }
          report.stages.push_back(
              {"bounce " + std::to_string(bounce) + " cascade " + std::to_string(i), watch.ms()});
          watch.restart();
        });
    // Cascade 0's probes are the covered texels: their irradiance on each side.
    const Grid& g0 = grids[0];
    const std::vector<Vec3>& d0 = dirs[0];
    if (!gathered)
      for_each_texel_probe(a, g0, [&](std::size_t k, std::uint64_t q) {
        // Irradiance over pi is the cosine-weighted mean (the core's normalised weights: a
        // uniform sky gives pi L on any map).
        const Vec3 n = g0.probes[q].local;
        Rgb f{}, bk{};
        cascade::cosine_mean(d0, n, c0, q, f);
        cascade::cosine_mean(d0, -n, c0, q, bk);
        next_front[k] = f * float(kPi);
        next_back[k] = bk * float(kPi);
      });
    out.front.swap(next_front);
    out.back.swap(next_back);
    if (o.keep_radiance && bounce == o.bounces) {
      const std::size_t nd = std::size_t(o.side0) * std::size_t(o.side0);
      out.side0 = o.side0;
      out.radiance.assign(n_texels * nd, Rgb{});
      for_each_texel_probe(a, g0, [&](std::size_t k, std::uint64_t q) {
        std::copy_n(c0.probe(q), nd, out.radiance.data() + k * nd);
      });
    }
    report.rays += traced.load();
    report.stages.push_back({"bounce " + std::to_string(bounce) + " irradiance", watch.ms()});
  }
  return out;
}

}  // namespace penumbra::spaceland::atlas
