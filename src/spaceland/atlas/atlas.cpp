#include "spaceland/atlas/atlas.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <queue>
#include <unordered_map>

#include "core/octahedral.hpp"
#include "io/json_reader.hpp"
#include "spaceland/color.hpp"

namespace penumbra::spaceland::atlas {

namespace {

constexpr double kPi = std::numbers::pi;

// How far, in texels, two triangles of a chart may run into each other before they count as
// overlapping (rounding of their shared edges).
constexpr float kOverlap = 1e-3f;
// How far apart, in texels, the planes of two of a chart's triangles sharing a texel may lie
// there (a smooth surface's neighbours at 45 degrees differ by up to about a texel).
constexpr float kHeight = 1.5f;

float cross2(Uv a, Uv b) {
  return a.x * b.y - a.y * b.x;
}

// The edge function of edge (a, b) at p, worked out from the edge's canonical order, so that the
// two triangles sharing it get exactly opposite values (a plain cross product from a and from b
// rounds differently, and a texel centre on the edge could fall in both or neither).
float edge(Uv a, Uv b, Uv p) {
  const bool ordered = a.x < b.x || (a.x == b.x && a.y < b.y);
  const Uv lo = ordered ? a : b, hi = ordered ? b : a;
  const float e = cross2({hi.x - lo.x, hi.y - lo.y}, {p.x - lo.x, p.y - lo.y});
  return ordered ? e : -e;
}

// Whether p lies in the counter-clockwise triangle (a, b, c): inside every edge, and on an edge
// only where that edge runs downwards or, level, leftwards (of two triangles sharing an edge,
// exactly one owns the points on it).
bool inside(const std::array<Uv, 3>& t, Uv p) {
  for (int k = 0; k < 3; ++k) {
    const Uv a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
    const float e = edge(a, b, p);
    if (e > 0) continue;
    if (e < 0) return false;
    const float dx = b.x - a.x, dy = b.y - a.y;
    if (!(dy < 0 || (dy == 0 && dx < 0))) return false;
  }
  return true;
}

// The triangle in counter-clockwise order (false: degenerate).
bool counter_clockwise(std::array<Uv, 3>& t) {
  const float area = cross2({t[1].x - t[0].x, t[1].y - t[0].y}, {t[2].x - t[0].x, t[2].y - t[0].y});
  if (!(area != 0)) return false;
  if (area < 0) std::swap(t[1], t[2]);
  return true;
}

// Calls f(i, j) for every texel whose centre (i + 1/2, j + 1/2) the triangle holds: row by row,
// over the span the row's centre line crosses (a long sliver costs its texels, not its box).
template <class F>
void for_each_texel(std::array<Uv, 3> t, F&& f) {
  if (!counter_clockwise(t)) return;
  const float y0 = std::min({t[0].y, t[1].y, t[2].y}), y1 = std::max({t[0].y, t[1].y, t[2].y});
  for (int j = int(std::floor(y0 - 0.5f)); j <= int(std::ceil(y1 - 0.5f)); ++j) {
    const float y = float(j) + 0.5f;
    float x0 = INFINITY, x1 = -INFINITY;
    for (int k = 0; k < 3; ++k) {
      const Uv a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
      if ((a.y - y) * (b.y - y) > 0) continue;  // the edge lies above or below the line
      if (a.y == b.y) {
        x0 = std::min({x0, a.x, b.x}), x1 = std::max({x1, a.x, b.x});
        continue;
      }
      const float x = a.x + (b.x - a.x) * ((y - a.y) / (b.y - a.y));
      x0 = std::min(x0, x), x1 = std::max(x1, x);
    }
    if (!(x0 <= x1)) continue;
    // A texel either side of the span, for the rounding of the crossings; inside() decides.
    for (int i = int(std::floor(x0 - 0.5f)) - 1; i <= int(std::ceil(x1 - 0.5f)) + 1; ++i)
      if (inside(t, {float(i) + 0.5f, y})) f(i, j);
  }
}

// Calls f(i, j) for every texel whose square [i, i + 1] x [j, j + 1] the triangle touches
// (conservative coverage): row by row, the x-extent of the triangle clipped to the row.
template <class F>
void for_each_touched(const std::array<Uv, 3>& t, F&& f) {
  const float y0 = std::min({t[0].y, t[1].y, t[2].y}), y1 = std::max({t[0].y, t[1].y, t[2].y});
  // Rows and columns it only meets along their edge at its top or right are left out: the
  // chart's rectangle ends there.
  const int j0 = int(std::floor(y0)), j1 = std::max(j0, int(std::ceil(y1)) - 1);
  for (int j = j0; j <= j1; ++j) {
    const float lo = float(j), hi = float(j + 1);
    float x0 = INFINITY, x1 = -INFINITY;
    for (int k = 0; k < 3; ++k) {
      const Uv a = t[std::size_t(k)], b = t[std::size_t((k + 1) % 3)];
      if (a.y >= lo && a.y <= hi) x0 = std::min(x0, a.x), x1 = std::max(x1, a.x);
      for (float y : {lo, hi})
        if ((a.y - y) * (b.y - y) < 0) {
          const float x = a.x + (b.x - a.x) * ((y - a.y) / (b.y - a.y));
          x0 = std::min(x0, x), x1 = std::max(x1, x);
        }
    }
    if (!(x0 <= x1)) continue;
    const int i0 = int(std::floor(x0)), i1 = std::max(i0, int(std::ceil(x1)) - 1);
    for (int i = i0; i <= i1; ++i) f(i, j);
  }
}

// Whether two triangles' interiors overlap by more than `eps` (texels): no edge normal of either
// separates them (the separating axis test; triangles that share an edge or a corner touch and
// do not overlap).
bool overlap(const std::array<Uv, 3>& a, const std::array<Uv, 3>& b, float eps) {
  for (const std::array<Uv, 3>* t : {&a, &b})
    for (int k = 0; k < 3; ++k) {
      const Uv p = (*t)[std::size_t(k)], q = (*t)[std::size_t((k + 1) % 3)];
      const float nx = q.y - p.y, ny = p.x - q.x;
      const float len = std::sqrt(nx * nx + ny * ny);
      if (!(len > 0)) continue;
      float a0 = INFINITY, a1 = -INFINITY, b0 = INFINITY, b1 = -INFINITY;
      for (const Uv& v : a) {
        const float d = (v.x * nx + v.y * ny) / len;
        a0 = std::min(a0, d), a1 = std::max(a1, d);
      }
      for (const Uv& v : b) {
        const float d = (v.x * nx + v.y * ny) / len;
        b0 = std::min(b0, d), b1 = std::max(b1, d);
      }
      if (a1 <= b0 + eps || b1 <= a0 + eps) return false;
    }
  return true;
}

// Barycentric coordinates of p in the 2D triangle t (its area non-zero).
std::array<float, 3> barycentric(const std::array<Uv, 3>& t, Uv p) {
  const float area = cross2({t[1].x - t[0].x, t[1].y - t[0].y}, {t[2].x - t[0].x, t[2].y - t[0].y});
  const float b1 = cross2({p.x - t[0].x, p.y - t[0].y}, {t[2].x - t[0].x, t[2].y - t[0].y}) / area;
  const float b2 = cross2({t[1].x - t[0].x, t[1].y - t[0].y}, {p.x - t[0].x, p.y - t[0].y}) / area;
  return {1 - b1 - b2, b1, b2};
}

// The point of the 2D triangle nearest p, as barycentric coordinates.
std::array<float, 3> nearest(const std::array<Uv, 3>& t, Uv p) {
  const std::array<float, 3> b = barycentric(t, p);
  if (b[0] >= 0 && b[1] >= 0 && b[2] >= 0) return b;
  std::array<float, 3> best{};
  float best_d = INFINITY;
  for (int k = 0; k < 3; ++k) {
    const Uv a = t[std::size_t(k)], c = t[std::size_t((k + 1) % 3)];
    const float ex = c.x - a.x, ey = c.y - a.y, l2 = ex * ex + ey * ey;
    const float s =
        l2 > 0 ? std::clamp(((p.x - a.x) * ex + (p.y - a.y) * ey) / l2, 0.0f, 1.0f) : 0.0f;
    const float dx = a.x + s * ex - p.x, dy = a.y + s * ey - p.y, d = dx * dx + dy * dy;
    if (d < best_d) {
      best_d = d;
      best = {};
      best[std::size_t(k)] = 1 - s;
      best[std::size_t((k + 1) % 3)] = s;
    }
  }
  return best;
}

// The height over the chart's plane at p of the plane through a triangle's corners (heights h).
float at_height(const std::array<Uv, 3>& t, const std::array<float, 3>& h, Uv p) {
  const std::array<float, 3> b = barycentric(t, p);
  return b[0] * h[0] + b[1] * h[1] + b[2] * h[2];
}

std::uint64_t cell(int i, int j) {
  return std::uint64_t(std::uint32_t(i)) << 32 | std::uint32_t(j);
}

// A mesh's vertices welded by position (a box's faces have their own copies of its corners) and
// its triangles' neighbours across their edges.
struct Topology {
  std::vector<std::uint32_t> weld;  // per position: its welded vertex
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> edges;  // welded (lo, hi)
  static std::uint64_t key(std::uint32_t a, std::uint32_t b) {
    return std::uint64_t(std::min(a, b)) << 32 | std::max(a, b);
  }
  std::uint64_t edge_key(const TriangleMesh& m, std::uint32_t t, int k) const {
    const auto& tri = m.triangles[t];
    return key(weld[tri[std::size_t(k)]], weld[tri[std::size_t((k + 1) % 3)]]);
  }
};

// With `lightmap`, vertices weld where their lightmap coordinates are the same too: the edges
// then join the triangles of one lightmap island.
Topology topology(const TriangleMesh& m, bool lightmap = false) {
  Topology top;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> by_hash;
  top.weld.resize(m.positions.size());
  const auto same_vertex = [&](std::uint32_t a, std::uint32_t b) {
    return m.positions[a] == m.positions[b] &&
           (!lightmap || m.lightmap_uvs[a] == m.lightmap_uvs[b]);
  };
  for (std::uint32_t k = 0; k < m.positions.size(); ++k) {
    const Vec3 p = m.positions[k];
    std::uint32_t bits[5] = {};
    std::memcpy(bits, &p, sizeof(Vec3));
    if (lightmap) std::memcpy(bits + 3, m.lightmap_uvs[k].data(), 2 * sizeof(float));
    const std::uint64_t h = (std::uint64_t(bits[0]) * 0x9E3779B97F4A7C15ull) ^
                            (std::uint64_t(bits[1]) * 0xC2B2AE3D27D4EB4Full) ^
                            (std::uint64_t(bits[2]) * 0x165667B19E3779F9ull) ^
                            (std::uint64_t(bits[3]) * 0x27D4EB2F165667C5ull) ^
                            (std::uint64_t(bits[4]) * 0x94D049BB133111EBull);
    std::vector<std::uint32_t>& same = by_hash[h];
    top.weld[k] = k;
    for (std::uint32_t o : same)
      if (same_vertex(o, k)) {
        top.weld[k] = o;
        break;
      }
    if (top.weld[k] == k) same.push_back(k);
  }
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) top.edges[top.edge_key(m, t, k)].push_back(t);
  return top;
}

// Closes a mesh chart: the rectangle of whole frame texels around its triangles (until packed,
// the frame's texel (ox, oy) is its first), its triangles listed.
void add_chart(Chart c, const std::vector<std::uint32_t>& members,
               const std::vector<std::array<Uv, 3>>& uv, Atlas& a) {
  float x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (std::uint32_t t : members)
    for (const Uv& p : uv[t]) {
      x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
      y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    }
  const int ox = int(std::floor(x0)), oy = int(std::floor(y0));
  c.width = std::max(1, int(std::ceil(x1)) - ox);
  c.height = std::max(1, int(std::ceil(y1)) - oy);
  c.shift_x = -ox;
  c.shift_y = -oy;
  c.first = std::uint32_t(a.chart_triangles.size());
  c.count = std::uint32_t(members.size());
  a.chart_triangles.insert(a.chart_triangles.end(), members.begin(), members.end());
  a.charts.push_back(c);
}

// A mesh's charts from its lightmap UVs: one per island (triangles joined by edges whose ends
// share position and lightmap coordinates), its coordinates scaled to the texel size by the
// island's world area over its UV area. False, and nothing added, where an island has no UV area
// or overlaps itself (lightmap UVs must be unique; mirrored texture UVs are not).
bool chart_lightmap(const Scene& scene, std::uint32_t mi, float ts, Atlas& a) {
  const TriangleMesh& m = scene.meshes[mi];
  const std::size_t n = m.triangles.size(), charts0 = a.charts.size(),
                    triangles0 = a.chart_triangles.size();
  const Topology top = topology(m, true);
  std::vector<std::uint32_t>& chart_of = a.triangle_chart[mi];
  std::vector<std::array<Uv, 3>>& uv = a.triangle_uv[mi];
  chart_of.assign(n, std::uint32_t(-1));
  uv.assign(n, {});
  const auto fail = [&] {
    a.charts.resize(charts0);
    a.chart_triangles.resize(triangles0);
    return false;
  };
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> touching;
  std::vector<std::uint32_t> members;
  for (std::uint32_t seed = 0; seed < n; ++seed) {
    if (chart_of[seed] != std::uint32_t(-1)) continue;
    const std::uint32_t id = std::uint32_t(a.charts.size());
    members.assign(1, seed);
    chart_of[seed] = id;
    for (std::size_t q = 0; q < members.size(); ++q)
      for (int k = 0; k < 3; ++k)
        for (std::uint32_t o : top.edges.at(top.edge_key(m, members[q], k)))
          if (chart_of[o] == std::uint32_t(-1)) {
            chart_of[o] = id;
            members.push_back(o);
          }
    Chart c;
    c.kind = ChartKind::mesh;
    c.shape = mi;
    c.object = m.object;
    c.from_lightmap = true;
    double uv_area = 0;
    for (std::uint32_t t : members) {
      const auto& tri = m.triangles[t];
      c.area += 0.5 * double(length(cross(m.positions[tri[1]] - m.positions[tri[0]],
                                          m.positions[tri[2]] - m.positions[tri[0]])));
      const auto& p0 = m.lightmap_uvs[tri[0]];
      const auto& p1 = m.lightmap_uvs[tri[1]];
      const auto& p2 = m.lightmap_uvs[tri[2]];
      uv_area +=
          0.5 *
          std::abs(double(cross2({p1[0] - p0[0], p1[1] - p0[1]}, {p2[0] - p0[0], p2[1] - p0[1]})));
    }
    if (!(uv_area > 0)) {
      if (c.area > 0) return fail();
      uv_area = 1;  // an island of no area: its corners anywhere
    }
    const float scale = float(std::sqrt(c.area / uv_area)) / ts;
    touching.clear();
    for (std::uint32_t t : members) {
      std::array<Uv, 3>& p = uv[t];
      for (int k = 0; k < 3; ++k) {
        const auto& l = m.lightmap_uvs[m.triangles[t][std::size_t(k)]];
        p[std::size_t(k)] = {l[0] * scale, l[1] * scale};
      }
      bool free = true;
      for_each_touched(p, [&](int i, int j) {
        const auto it = touching.find(cell(i, j));
        if (it == touching.end()) return;
        for (std::uint32_t o : it->second) free = free && !overlap(p, uv[o], kOverlap);
      });
      if (!free) return fail();
      for_each_touched(p, [&](int i, int j) { touching[cell(i, j)].push_back(t); });
    }
    add_chart(c, members, uv, a);
  }
  return true;
}

// Grows one mesh's charts (ChartKind::mesh) and the frame coordinates of its triangles.
void chart_mesh(const Scene& scene, std::uint32_t mi, float ts, float cos_max, Atlas& a) {
  const TriangleMesh& m = scene.meshes[mi];
  const std::size_t n = m.triangles.size();
  const Topology top = topology(m);
  std::vector<Vec3> normal(n);
  std::vector<double> area(n);
  for (std::size_t t = 0; t < n; ++t) {
    const auto& tri = m.triangles[t];
    const Vec3 c =
        cross(m.positions[tri[1]] - m.positions[tri[0]], m.positions[tri[2]] - m.positions[tri[0]]);
    area[t] = 0.5 * double(length(c));
    normal[t] = area[t] > 0 ? normalize(c) : Vec3{};
  }
  // Seeds in order of decreasing area (ties by index): the big flat parts get their charts first.
  std::vector<std::uint32_t> order(n);
  for (std::uint32_t t = 0; t < n; ++t) order[t] = t;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t x, std::uint32_t y) { return area[x] > area[y]; });
  std::vector<std::uint32_t>& chart_of = a.triangle_chart[mi];
  std::vector<std::array<Uv, 3>>& uv = a.triangle_uv[mi];
  chart_of.assign(n, std::uint32_t(-1));
  uv.assign(n, {});
  // Per texel cell the chart's triangles touching it, to find those a new one could overlap.
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> touching;
  std::vector<std::uint32_t> members;
  // The heights over their chart's plane of the triangles it holds (height() below).
  std::vector<std::array<float, 3>> heights(n);
  for (std::uint32_t seed : order) {
    if (chart_of[seed] != std::uint32_t(-1)) continue;
    const auto& st = m.triangles[seed];
    Chart c;
    c.kind = ChartKind::mesh;
    c.shape = mi;
    c.object = m.object;
    c.origin = m.positions[st[0]];
    if (area[seed] > 0) {
      // u along the longer side of the seed's corner nearest a right angle: a box's or a quad's
      // face (two right triangles) gets a tight rectangle, not one about its diagonal.
      Vec3 side{};
      float best = INFINITY;
      for (int k = 0; k < 3; ++k) {
        const Vec3 p = m.positions[st[std::size_t(k)]];
        const Vec3 e1 = m.positions[st[std::size_t((k + 1) % 3)]] - p;
        const Vec3 e2 = m.positions[st[std::size_t((k + 2) % 3)]] - p;
        const float cosine = std::abs(dot(e1, e2)) / (length(e1) * length(e2));
        if (cosine < best) {
          best = cosine;
          side = dot(e1, e1) >= dot(e2, e2) ? e1 : e2;
        }
      }
      c.n = normal[seed];
      c.u = normalize(side - c.n * dot(side, c.n));
      c.v = cross(c.n, c.u);
    } else {
      c.n = {0, 0, 1};
      orthonormal_basis(c.n, c.u, c.v);
    }
    // A triangle's corners' heights over the chart's plane, texels.
    const auto height = [&](std::uint32_t t) {
      std::array<float, 3> out;
      for (int k = 0; k < 3; ++k)
        out[std::size_t(k)] = dot(m.positions[m.triangles[t][std::size_t(k)]] - c.origin, c.n) / ts;
      return out;
    };
    const auto project = [&](std::uint32_t t) {
      std::array<Uv, 3> out;
      for (int k = 0; k < 3; ++k) {
        const Vec3 d = m.positions[m.triangles[t][std::size_t(k)]] - c.origin;
        out[std::size_t(k)] = {dot(d, c.u) / ts, dot(d, c.v) / ts};
      }
      return out;
    };
    touching.clear();
    members.clear();
    const std::uint32_t id = std::uint32_t(a.charts.size());
    // Breadth first from the seed over shared edges.
    std::queue<std::uint32_t> queue;
    const auto take = [&](std::uint32_t t) {
      const std::array<Uv, 3> p = project(t);
      if (area[t] > 0) {
        if (dot(normal[t], c.n) < cos_max) return false;
        // Left for another chart where it would cover part of one of this chart's triangles
        // (a surface folding back over itself within the normal cone), or share a texel with
        // one that lies at another height there (two parts a texel apart on the chart's plane
        // but not in space: a texel between them would hold a point of one for hits on both).
        const std::array<float, 3> h = height(t);
        heights[t] = h;
        bool free = true;
        for_each_touched(p, [&](int i, int j) {
          if (!free) return;
          const auto it = touching.find(cell(i, j));
          if (it == touching.end()) return;
          const Uv centre{float(i) + 0.5f, float(j) + 0.5f};
          const float here = at_height(p, h, centre);
          for (std::uint32_t o : it->second)
            if (overlap(p, uv[o], kOverlap) ||
                !(std::abs(at_height(uv[o], heights[o], centre) - here) <= kHeight)) {
              free = false;
              return;
            }
        });
        if (!free) return false;
        for_each_touched(p, [&](int i, int j) { touching[cell(i, j)].push_back(t); });
      }
      chart_of[t] = id;
      uv[t] = p;
      members.push_back(t);
      queue.push(t);
      return true;
    };
    take(seed);
    while (!queue.empty()) {
      const std::uint32_t t = queue.front();
      queue.pop();
      for (int k = 0; k < 3; ++k)
        for (std::uint32_t o : top.edges.at(top.edge_key(m, t, k)))
          if (chart_of[o] == std::uint32_t(-1)) take(o);
    }
    for (std::uint32_t t : members) c.area += area[t];
    add_chart(c, members, uv, a);
  }
}

Chart shape_chart(ChartKind kind, std::uint32_t shape, int object) {
  Chart c;
  c.kind = kind;
  c.shape = shape;
  c.object = object;
  return c;
}

// The refusal of an atlas that would pass its largest side: `what` it would need.
Error too_large(const std::string& what, float ts, int max_side) {
  return Error{"the surface atlas would need " + what + " at " + io::format_number(ts) +
               " world units a texel, more than its largest side of " + std::to_string(max_side) +
               " allows; use larger texels or fewer"};
}

// Shelf packing, tallest first: each chart's rectangle with its gutter on every side.
Status pack(Atlas& a, int max_side) {
  const int g = a.gutter;
  std::vector<std::uint32_t> order(a.charts.size());
  double sum = 0;
  int widest = 1;
  for (std::uint32_t k = 0; k < order.size(); ++k) {
    order[k] = k;
    const Chart& c = a.charts[k];
    sum += double(c.width + 2 * g) * double(c.height + 2 * g);
    widest = std::max(widest, c.width + 2 * g);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) {
    const Chart &cx = a.charts[x], &cy = a.charts[y];
    return cx.height != cy.height ? cx.height > cy.height : cx.width > cy.width;
  });
  const double side = std::ceil(std::sqrt(sum) * 1.05);
  if (widest > max_side || side > double(max_side))
    return too_large("a chart " + std::to_string(widest) + " texels wide and about " +
                         io::format_number(side) + " texels square",
                     a.texel_size, max_side);
  const int width = std::min(max_side, std::max(widest, int(side)));
  int x = 0, y = 0, shelf = 0;
  for (std::uint32_t k : order) {
    Chart& c = a.charts[k];
    const int w = c.width + 2 * g, h = c.height + 2 * g;
    if (x + w > width) {
      y += shelf;
      x = 0;
      shelf = 0;
    }
    const int fx = -c.shift_x, fy = -c.shift_y;  // the rectangle's first frame texel
    c.x = x + g;
    c.y = y + g;
    c.shift_x = c.x - fx;
    c.shift_y = c.y - fy;
    x += w;
    shelf = std::max(shelf, h);
  }
  const int height = y + shelf;
  if (height > max_side)
    return too_large(std::to_string(width) + " x " + std::to_string(height) + " texels",
                     a.texel_size, max_side);
  a.width = width;
  a.height = height;
  return {};
}

// Texels per unit of distance to the nearest light, at least, where Options::refine allows.
constexpr double kLightTexels = 16;
// Whether surfaces of this material emit.
bool emits(const Scene& scene, std::uint32_t material) {
  return !is_black(scene.materials[material].emission);
}

// A tile's side, in its own texels, past which a quadtree node whose texels are refined is split
// (the finest tiles are 64 of their texels across: 2 texels of gutter each side cost 13%).
constexpr int kTile = 64;

// The refinement level (Options::refine) of a piece of surface whose nearest point lies d from
// the nearest light (from its centre, and no nearer than its radius: by a large light the light
// changes over its size): its texel at most d / kLightTexels, halving the atlas's texel (ts) as
// often as that takes. A light's irradiance changes over distances like the distance to it.
struct Density {
  std::vector<DensityLight> lights;
  int refine = 0;
  float ts = 0;

  int level_of(double d) const {
    if (!(d > 0)) return refine;
    const double finer = double(ts) * kLightTexels / d;
    if (!(finer > 1)) return 0;
    return std::min(refine, int(std::ceil(std::log2(finer))));
  }
  // Frame rectangle [x0, x1] x [y0, y1] (texels of size ts) of a plane (origin, u, v): the level
  // at its point nearest a light.
  int level(Vec3 origin, Vec3 u, Vec3 v, float x0, float y0, float x1, float y1) const {
    double best = INFINITY;
    for (const DensityLight& l : lights) {
      const Vec3 d = l.centre - origin;
      const float a = std::clamp(dot(d, u) / ts, x0, x1), b = std::clamp(dot(d, v) / ts, y0, y1);
      best = std::min(best, std::max(double(l.radius),
                                     double(length(l.centre - (origin + (u * a + v * b) * ts)))));
    }
    return level_of(best);
  }
};

// Whether a mesh triangle's frame box meets the rectangle [x0, x1) x [y0, y1).
bool box_meets(const std::array<Uv, 3>& t, float x0, float y0, float x1, float y1) {
  const float lx = std::min({t[0].x, t[1].x, t[2].x}), hx = std::max({t[0].x, t[1].x, t[2].x});
  const float ly = std::min({t[0].y, t[1].y, t[2].y}), hy = std::max({t[0].y, t[1].y, t[2].y});
  return lx < x1 && hx > x0 && ly < y1 && hy > y0;
}

// Refines the texels of every chart (Density): a chart whose level is the same all over keeps
// its shape at that level's texel; a planar one over which it changes is split into tiles, the
// leaves of a quadtree over its frame (Atlas::splits). Charts are renumbered.
void refine_charts(const Scene& scene, const Density& den, Atlas& a) {
  const float ts = a.texel_size;
  std::vector<Chart> old;
  old.swap(a.charts);
  std::vector<std::uint32_t> old_triangles;
  old_triangles.swap(a.chart_triangles);
  std::vector<std::uint32_t> members, inside;
  for (Chart c : old) {
    const std::uint32_t id = std::uint32_t(a.charts.size());
    members.clear();
    if (c.kind == ChartKind::mesh)
      members.assign(old_triangles.begin() + c.first, old_triangles.begin() + c.first + c.count);
    // A light's own surface is not refined: what it sends is its emission, not its texels'.
    bool light = true;
    if (c.kind == ChartKind::mesh) {
      const TriangleMesh& m = scene.meshes[c.shape];
      for (std::uint32_t t : members)
        light = light && emits(scene, m.materials.empty() ? 0 : m.materials[t]);
    } else {
      light = emits(scene, c.kind == ChartKind::disk ? scene.disks[c.shape].material
                                                     : scene.spheres[c.shape].material);
    }
    if (c.kind == ChartKind::sphere) {
      const Sphere& sp = scene.spheres[c.shape];
      double best = INFINITY;
      for (const DensityLight& l : den.lights)
        best = std::min(
            best, std::max(double(l.radius), double(length(l.centre - sp.center)) - sp.radius));
      c.level = light ? 0 : den.level_of(best);
      c.texel_size = std::ldexp(ts, -c.level);
      c.width = c.height = std::max(2, int(std::ceil(std::sqrt(c.area) / c.texel_size)));
      a.sphere_chart[c.shape] = id;
      a.charts.push_back(c);
      continue;
    }
    // The chart's frame rectangle [ox, ox + width) x [oy, oy + height), texels.
    const int ox = -c.shift_x, oy = -c.shift_y;
    int level = 0;
    if (c.kind == ChartKind::mesh && c.from_lightmap) {
      // No plane: from the triangles' corners and centres.
      const TriangleMesh& m = scene.meshes[c.shape];
      double best = INFINITY;
      for (const DensityLight& l : den.lights)
        for (std::uint32_t t : members) {
          const auto& tri = m.triangles[t];
          const Vec3 p0 = m.positions[tri[0]], p1 = m.positions[tri[1]], p2 = m.positions[tri[2]];
          for (Vec3 p : {p0, p1, p2, (p0 + p1 + p2) * (1.0f / 3)})
            best = std::min(best, std::max(double(l.radius), double(length(l.centre - p))));
        }
      level = den.level_of(best);
    } else {
      level = den.level(c.origin, c.u, c.v, float(ox), float(oy), float(ox + c.width),
                        float(oy + c.height));
    }
    if (light) level = 0;
    const bool planar = !(c.kind == ChartKind::mesh && c.from_lightmap);
    if (!planar || level == 0 ||
        (std::int64_t(std::max(c.width, c.height)) << level) <= std::int64_t(kTile)) {
      // One texel size over the chart.
      c.level = level;
      c.texel_size = std::ldexp(ts, -level);
      if (c.kind == ChartKind::disk) {
        const Disk& d = scene.disks[c.shape];
        c.width = c.height = std::max(1, int(std::ceil(2 * double(d.radius) / c.texel_size)));
        c.origin = d.center - (c.u + c.v) * (0.5f * float(c.width) * c.texel_size);
        a.disk_chart[c.shape] = id;
        a.charts.push_back(c);
        continue;
      }
      const float f = std::ldexp(1.0f, level);
      for (std::uint32_t t : members) {
        for (Uv& p : a.triangle_uv[c.shape][t]) p = {p.x * f, p.y * f};
        a.triangle_chart[c.shape][t] = id;
      }
      add_chart(c, members, a.triangle_uv[c.shape], a);
      continue;
    }
    // Split: a quadtree over the frame from a square of a power of two texels.
    const std::uint32_t k = std::uint32_t(a.splits.size());
    a.splits.push_back({c.origin, c.u, c.v, std::uint32_t(a.nodes.size())});
    int side = 1;
    while (side < std::max(c.width, c.height)) side *= 2;
    a.nodes.push_back({ox, oy, side});
    const int x_end = ox + c.width, y_end = oy + c.height;
    const auto split = [&](auto& self, std::size_t i) -> void {
      const Node n = a.nodes[i];
      const int x1 = std::min(n.x + n.side, x_end), y1 = std::min(n.y + n.side, y_end);
      if (x1 <= n.x || y1 <= n.y) return;  // past the chart's rectangle
      const int lv = den.level(c.origin, c.u, c.v, float(n.x), float(n.y), float(x1), float(y1));
      if (lv > 0 && n.side > 1 && (std::int64_t(n.side) << lv) > std::int64_t(kTile)) {
        const int half = n.side / 2;
        const std::size_t child = a.nodes.size();
        a.nodes[i].child = int(child);
        for (int q = 0; q < 4; ++q)
          a.nodes.push_back({n.x + (q & 1) * half, n.y + (q >> 1) * half, half});
        for (int q = 0; q < 4; ++q) self(self, child + std::size_t(q));
        return;
      }
      // A leaf: a tile where the surface meets it.
      inside.clear();
      if (c.kind == ChartKind::mesh) {
        for (std::uint32_t t : members)
          if (box_meets(a.triangle_uv[c.shape][t], float(n.x), float(n.y), float(x1), float(y1)))
            inside.push_back(t);
        if (inside.empty()) return;
      } else {
        // The disk's centre is the middle of its square; a texel's margin for rounding.
        const float r = scene.disks[c.shape].radius / ts + 1;
        const float cx = 0.5f * float(c.width), cy = 0.5f * float(c.height);
        const float dx = cx - std::clamp(cx, float(n.x), float(x1));
        const float dy = cy - std::clamp(cy, float(n.y), float(y1));
        if (dx * dx + dy * dy >= r * r) return;
      }
      Chart t = c;
      t.tile = true;
      t.tile_x = n.x;
      t.tile_y = n.y;
      t.level = lv;
      t.texel_size = std::ldexp(ts, -lv);
      t.origin = c.origin + (c.u * float(n.x) + c.v * float(n.y)) * ts;
      t.width = (x1 - n.x) << lv;
      t.height = (y1 - n.y) << lv;
      t.shift_x = t.shift_y = 0;
      t.area = 0;
      t.first = std::uint32_t(a.chart_triangles.size());
      t.count = std::uint32_t(inside.size());
      a.chart_triangles.insert(a.chart_triangles.end(), inside.begin(), inside.end());
      a.nodes[i].chart = int(a.charts.size());
      a.charts.push_back(t);
    };
    split(split, a.splits.back().root);
    if (c.kind == ChartKind::disk)
      a.disk_chart[c.shape] = Atlas::kSplit | k;
    else
      for (std::uint32_t t : members) a.triangle_chart[c.shape][t] = Atlas::kSplit | k;
  }
}

}  // namespace

// The core's equal-area map (core/octahedral.hpp), from [-1, 1]^2 to the chart's [0, 1]^2: a
// sphere's texels then hold equal areas of it.
Uv octahedral(Vec3 d) {
  const std::array<float, 2> e = penumbra::octahedral::encode(d);
  return {0.5f * e[0] + 0.5f, 0.5f * e[1] + 0.5f};
}

Vec3 from_octahedral(Uv p) {
  return penumbra::octahedral::decode(2 * double(p.x) - 1, 2 * double(p.y) - 1);
}

double surface_area(const Scene& scene) {
  double total = 0;
  for (const TriangleMesh& m : scene.meshes)
    for (const auto& t : m.triangles)
      total += 0.5 * double(length(cross(m.positions[t[1]] - m.positions[t[0]],
                                         m.positions[t[2]] - m.positions[t[0]])));
  for (const Disk& d : scene.disks) total += kPi * double(d.radius) * d.radius;
  for (const Sphere& s : scene.spheres) total += 4 * kPi * double(s.radius) * s.radius;
  return total;
}

std::vector<DensityLight> density_lights(const Scene& scene) {
  std::vector<DensityLight> out;
  for (const Sphere& sp : scene.spheres)
    if (emits(scene, sp.material)) out.push_back({sp.center, sp.radius});
  for (const Disk& d : scene.disks)
    if (emits(scene, d.material)) out.push_back({d.center, d.radius});
  for (const TriangleMesh& m : scene.meshes) {
    // The middle of the box around its emitting triangles.
    Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
      if (emits(scene, m.materials.empty() ? 0 : m.materials[t]))
        for (std::uint32_t v : m.triangles[t]) {
          lo = min(lo, m.positions[v]);
          hi = max(hi, m.positions[v]);
        }
    if (lo.x <= hi.x) out.push_back({(lo + hi) * 0.5f, 0.5f * length(hi - lo)});
  }
  for (const Medium& md : scene.media)
    if (!is_black(md.emission)) out.push_back({md.center, length(md.half_size)});
  return out;
}

namespace {

// The charts at texel size ts (refined where den.refine > 0), not yet packed; `plain` and
// `refined`: the texels of their rectangles before and after refining.
Expected<Atlas> chart_all(const Scene& scene, const Options& o, float ts, const Density& den,
                          double& plain, double& refined) {
  Atlas a;
  a.gutter = o.gutter;
  a.texel_size = ts;
  // Refused before any chart is grown: the surface alone would pass the atlas's texels.
  const double need = surface_area(scene) / (double(ts) * ts);
  if (need > double(o.max_side) * o.max_side)
    return too_large("about " + io::format_number(need) + " texels", ts, o.max_side);
  const float cos_max = float(std::cos(double(o.max_angle) * kPi / 180));
  a.triangle_chart.resize(scene.meshes.size());
  a.triangle_uv.resize(scene.meshes.size());
  for (std::uint32_t mi = 0; mi < scene.meshes.size(); ++mi)
    if (scene.meshes[mi].lightmap_uvs.empty() || !chart_lightmap(scene, mi, ts, a))
      chart_mesh(scene, mi, ts, cos_max, a);
  for (std::uint32_t k = 0; k < scene.disks.size(); ++k) {
    const Disk& d = scene.disks[k];
    Chart c = shape_chart(ChartKind::disk, k, d.object);
    c.n = d.normal;
    orthonormal_basis(c.n, c.u, c.v);
    const double side = std::ceil(2 * double(d.radius) / ts);
    if (side > o.max_side)
      return too_large(io::format_number(side) + " texels across a disk", ts, o.max_side);
    c.width = c.height = std::max(1, int(side));
    // Centred in its square.
    c.origin = d.center - (c.u + c.v) * (0.5f * float(c.width) * ts);
    c.area = kPi * double(d.radius) * d.radius;
    a.disk_chart.push_back(std::uint32_t(a.charts.size()));
    a.charts.push_back(c);
  }
  for (std::uint32_t k = 0; k < scene.spheres.size(); ++k) {
    const Sphere& s = scene.spheres[k];
    Chart c = shape_chart(ChartKind::sphere, k, s.object);
    c.origin = s.center;
    c.area = 4 * kPi * double(s.radius) * s.radius;
    const double side = std::ceil(std::sqrt(c.area) / ts);
    if (side > o.max_side)
      return too_large(io::format_number(side) + " texels across a sphere", ts, o.max_side);
    c.width = c.height = std::max(2, int(side));
    a.sphere_chart.push_back(std::uint32_t(a.charts.size()));
    a.charts.push_back(c);
  }
  const auto texels = [&] {
    double n = 0;
    for (const Chart& c : a.charts) n += double(c.width) * double(c.height);
    return n;
  };
  plain = texels();
  for (Chart& c : a.charts) c.texel_size = ts;
  if (den.refine > 0 && !den.lights.empty()) {
    Density here = den;
    here.ts = ts;
    refine_charts(scene, here, a);
  }
  refined = texels();
  return a;
}

}  // namespace

Expected<Atlas> make_atlas(const Scene& scene, const Options& o) {
  if (!(o.texel_size >= 0) || !std::isfinite(o.texel_size))
    return Error{"`atlas.texel_size`: expected a size >= 0 (0: from the texel budget), found " +
                 io::format_number(o.texel_size)};
  if (o.texel_size == 0 && o.texels < 1)
    return Error{"`atlas.texels`: expected a budget of at least one texel"};
  if (o.gutter < 0 || o.gutter > 64)
    return Error{"`atlas.gutter`: expected 0..64 texels, found " + std::to_string(o.gutter)};
  if (!(o.max_angle > 0 && o.max_angle <= 80))
    return Error{"`atlas.max_angle`: expected degrees in (0, 80], found " +
                 io::format_number(o.max_angle)};
  if (o.max_side < 1 || o.max_side > 65536)
    return Error{"`atlas.max_side`: expected 1..65536 texels, found " + std::to_string(o.max_side)};
  if (o.refine < 0 || o.refine > 10)
    return Error{"`atlas.refine`: expected 0..10 levels, found " + std::to_string(o.refine)};
  const double total = surface_area(scene);
  float ts = o.texel_size > 0 ? o.texel_size : float(std::sqrt(total / double(o.texels)));
  if (!(ts > 0)) ts = 1;  // no surface: an empty atlas
  Density den;
  den.refine = o.refine;
  if (o.refine > 0) den.lights = density_lights(scene);
  double plain = 0, refined = 0;
  Expected<Atlas> a = chart_all(scene, o, ts, den, plain, refined);
  // A budget holds the refined texels: the coarsest texel grows by the ratio's square root, twice
  // at most (the larger texel is refined a little further). Where the lights' texels alone pass
  // twice the budget (they do not shrink as the coarsest texel grows), one level less.
  const double budget = plain;
  const float ts0 = ts;
  while (a && o.texel_size == 0 && refined > 1.05 * budget) {
    for (int pass = 0; pass < 2 && a && refined > 1.05 * budget; ++pass) {
      ts *= float(std::sqrt(refined / budget));
      a = chart_all(scene, o, ts, den, plain, refined);
    }
    if (!a || refined <= 2 * budget || den.refine == 0) break;
    --den.refine;
    ts = ts0;
    a = chart_all(scene, o, ts, den, plain, refined);
  }
  if (!a) return a.error();
  a->refine = den.refine;
  if (Status st = pack(*a, o.max_side); !st) return st.error();
  return a;
}

Uv Atlas::in_tile(std::uint32_t k, Uv p, std::uint32_t& chart) const {
  int id = tile_at(k, p);
  if (id < 0) {
    // Rounding past every tile (a hit on the rim of an empty leaf): the split's first tile, far
    // off its texels, which lookups answer with its nearest covered texel or nothing.
    id = nodes[splits[k].root].chart;
    for (std::size_t i = splits[k].root; id < 0 && i < nodes.size(); ++i) id = nodes[i].chart;
  }
  chart = std::uint32_t(id);
  const Chart& c = charts[chart];
  return {float(c.shift_x) + p.x, float(c.shift_y) + p.y};
}

int Atlas::tile_at(std::uint32_t k, Uv& p) const {
  const Node* n = &nodes[splits[k].root];
  while (n->child >= 0) {
    const int half = n->side / 2;
    const int q = (p.x >= float(n->x + half) ? 1 : 0) + (p.y >= float(n->y + half) ? 2 : 0);
    n = &nodes[std::size_t(n->child + q)];
  }
  if (n->chart < 0) return -1;
  const Chart& c = charts[std::size_t(n->chart)];
  const float f = std::ldexp(1.0f, c.level);
  p = {(p.x - float(c.tile_x)) * f, (p.y - float(c.tile_y)) * f};
  return n->chart;
}

std::array<Uv, 3> Atlas::chart_uv(const Chart& c, std::uint32_t t) const {
  std::array<Uv, 3> uv = triangle_uv[c.shape][t];
  if (!c.tile) return uv;
  const float f = std::ldexp(1.0f, c.level);
  for (Uv& p : uv) p = {(p.x - float(c.tile_x)) * f, (p.y - float(c.tile_y)) * f};
  return uv;
}

Uv Atlas::locate(const Scene& scene, const Hit& hit, std::uint32_t& chart) const {
  switch (hit.kind) {
    case ShapeKind::sphere: {
      chart = sphere_chart[hit.shape];
      const Chart& c = charts[chart];
      const Uv p = octahedral(normalize(hit.position - scene.spheres[hit.shape].center));
      return {float(c.shift_x) + p.x * float(c.width), float(c.shift_y) + p.y * float(c.height)};
    }
    case ShapeKind::disk: {
      chart = disk_chart[hit.shape];
      if (chart & kSplit) {
        const Split& sp = splits[chart & ~kSplit];
        const Vec3 d = hit.position - sp.origin;
        Uv p{dot(d, sp.u) / texel_size, dot(d, sp.v) / texel_size};
        return in_tile(chart & ~kSplit, p, chart);
      }
      const Chart& c = charts[chart];
      const Vec3 d = hit.position - c.origin;
      return {float(c.shift_x) + dot(d, c.u) / c.texel_size,
              float(c.shift_y) + dot(d, c.v) / c.texel_size};
    }
    default: {
      const TriangleMesh& m = scene.meshes[hit.shape];
      chart = triangle_chart[hit.shape][hit.primitive];
      const auto& t = m.triangles[hit.primitive];
      const std::array<Uv, 3>& uv = triangle_uv[hit.shape][hit.primitive];
      // Barycentric coordinates of the point in the triangle's plane.
      const Vec3 e1 = m.positions[t[1]] - m.positions[t[0]];
      const Vec3 e2 = m.positions[t[2]] - m.positions[t[0]];
      const Vec3 d = hit.position - m.positions[t[0]];
      const float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
      const float d1 = dot(d, e1), d2 = dot(d, e2);
      const float den = d11 * d22 - d12 * d12;
      float b1 = 0, b2 = 0;
      if (den > 0) {
        b1 = (d22 * d1 - d12 * d2) / den;
        b2 = (d11 * d2 - d12 * d1) / den;
      }
      const float b0 = 1 - b1 - b2;
      Uv p{b0 * uv[0].x + b1 * uv[1].x + b2 * uv[2].x, b0 * uv[0].y + b1 * uv[1].y + b2 * uv[2].y};
      if (chart & kSplit) return in_tile(chart & ~kSplit, p, chart);
      const Chart& c = charts[chart];
      return {float(c.shift_x) + p.x, float(c.shift_y) + p.y};
    }
  }
}

std::vector<Texel> rasterise(const Scene& scene, const Atlas& a) {
  std::vector<Texel> out(std::size_t(a.width) * std::size_t(a.height));
  const auto at = [&](int x, int y) -> Texel& {
    return out[std::size_t(y) * std::size_t(a.width) + std::size_t(x)];
  };
  // Per texel, how far the nearest triangle touching it lies from its centre (texels squared).
  std::vector<float> best(out.size(), INFINITY);
  for (std::uint32_t id = 0; id < a.charts.size(); ++id) {
    const Chart& c = a.charts[id];
    switch (c.kind) {
      case ChartKind::mesh: {
        const TriangleMesh& m = scene.meshes[c.shape];
        const auto point = [&](std::uint32_t t, const std::array<float, 3>& b) {
          const auto& tri = m.triangles[t];
          return m.positions[tri[0]] * b[0] + m.positions[tri[1]] * b[1] +
                 m.positions[tri[2]] * b[2];
        };
        // A triangle's unit normal; false where it has no area (nothing to hold a texel).
        const auto normal = [&](std::uint32_t t, Vec3& n) {
          const auto& tri = m.triangles[t];
          const Vec3 cr = cross(m.positions[tri[1]] - m.positions[tri[0]],
                                m.positions[tri[2]] - m.positions[tri[0]]);
          if (!(dot(cr, cr) > 0)) return false;
          n = normalize(cr);
          return true;
        };
        // Within the chart's rectangle (a tile's triangles run on past it).
        const auto mine = [&](int i, int j) {
          const int x = c.shift_x + i - c.x, y = c.shift_y + j - c.y;
          return x >= 0 && y >= 0 && x < c.width && y < c.height;
        };
        // Texels whose centre a triangle holds: that point.
        for (std::uint32_t k = c.first; k < c.first + c.count; ++k) {
          const std::uint32_t t = a.chart_triangles[k];
          const std::array<Uv, 3> uv = a.chart_uv(c, t);
          Vec3 n;
          if (!normal(t, n)) continue;
          for_each_texel(uv, [&](int i, int j) {
            if (!mine(i, j)) return;
            Texel& x = at(c.shift_x + i, c.shift_y + j);
            x.chart = int(id);
            ++x.claims;
            x.position = point(t, barycentric(uv, {float(i) + 0.5f, float(j) + 0.5f}));
            x.normal = n;
            x.material = m.materials.empty() ? 0 : m.materials[t];
          });
        }
        // Texels a triangle touches without holding their centre (along the chart's border, and
        // all of a part thinner than a texel): the nearest point of the triangles touching them.
        for (std::uint32_t k = c.first; k < c.first + c.count; ++k) {
          const std::uint32_t t = a.chart_triangles[k];
          const std::array<Uv, 3> uv = a.chart_uv(c, t);
          Vec3 n;
          if (!normal(t, n) || !(cross2({uv[1].x - uv[0].x, uv[1].y - uv[0].y},
                                        {uv[2].x - uv[0].x, uv[2].y - uv[0].y}) != 0))
            continue;
          for_each_touched(uv, [&](int i, int j) {
            if (!mine(i, j)) return;
            Texel& x = at(c.shift_x + i, c.shift_y + j);
            if (x.claims > 0) return;
            const Uv centre{float(i) + 0.5f, float(j) + 0.5f};
            const std::array<float, 3> b = nearest(uv, centre);
            const float px = b[0] * uv[0].x + b[1] * uv[1].x + b[2] * uv[2].x - centre.x;
            const float py = b[0] * uv[0].y + b[1] * uv[1].y + b[2] * uv[2].y - centre.y;
            const std::size_t at_k =
                std::size_t(c.shift_y + j) * std::size_t(a.width) + std::size_t(c.shift_x + i);
            if (!(px * px + py * py < best[at_k])) return;
            best[at_k] = px * px + py * py;
            x.chart = int(id);
            x.position = point(t, b);
            x.normal = n;
            x.material = m.materials.empty() ? 0 : m.materials[t];
          });
        }
        break;
      }
      case ChartKind::disk: {
        const Disk& d = scene.disks[c.shape];
        for (int j = 0; j < c.height; ++j)
          for (int i = 0; i < c.width; ++i) {
            const Vec3 q =
                c.origin + (c.u * (float(i) + 0.5f) + c.v * (float(j) + 0.5f)) * c.texel_size;
            if (length(q - d.center) > d.radius) continue;
            Texel& x = at(c.shift_x + i, c.shift_y + j);
            x.chart = int(id);
            ++x.claims;
            x.position = q;
            x.normal = d.normal;
            x.material = d.material;
          }
        break;
      }
      case ChartKind::sphere: {
        const Sphere& s = scene.spheres[c.shape];
        for (int j = 0; j < c.height; ++j)
          for (int i = 0; i < c.width; ++i) {
            const Vec3 dir = from_octahedral(
                {(float(i) + 0.5f) / float(c.width), (float(j) + 0.5f) / float(c.height)});
            Texel& x = at(c.shift_x + i, c.shift_y + j);
            x.chart = int(id);
            ++x.claims;
            x.position = s.center + dir * s.radius;
            x.normal = dir;
            x.material = s.material;
          }
        break;
      }
    }
  }
  return out;
}

Stats stats(const Scene& scene, const Atlas& a, const std::vector<Texel>& texels) {
  Stats s;
  s.charts = a.charts.size();
  for (const Chart& c : a.charts) s.lightmap_charts += c.from_lightmap;
  for (std::uint32_t mi = 0; mi < scene.meshes.size(); ++mi) {
    const TriangleMesh& m = scene.meshes[mi];
    const Topology top = topology(m);
    for (const auto& [key, tris] : top.edges) {
      (void)key;
      for (std::size_t k = 1; k < tris.size(); ++k)
        if (a.triangle_chart[mi][tris[k]] != a.triangle_chart[mi][tris[0]]) {
          ++s.seams;
          break;
        }
    }
  }
  std::uint64_t all = 0;
  for (const Texel& t : texels) all += t.chart >= 0;
  s.density_min = INFINITY;
  s.density_max = 0;
  for (const Chart& c : a.charts) {
    const double texel_area = double(c.texel_size) * c.texel_size;
    // Charts under a few texels are too coarse to measure a density on.
    if (c.area < 16 * texel_area) continue;
    // The chart's area in texels over the surface's: a mesh chart's triangles as projected, a
    // disk's map keeps areas, a sphere's square holds the whole sphere.
    double mapped = c.area / texel_area;
    if (c.kind == ChartKind::mesh) {
      mapped = 0;
      for (std::uint32_t k = c.first; k < c.first + c.count; ++k) {
        const std::array<Uv, 3> t = a.chart_uv(c, a.chart_triangles[k]);
        mapped += 0.5 * std::abs(double(cross2({t[1].x - t[0].x, t[1].y - t[0].y},
                                               {t[2].x - t[0].x, t[2].y - t[0].y})));
      }
    } else if (c.kind == ChartKind::sphere) {
      mapped = double(c.width) * double(c.height);
    }
    const double d = mapped * texel_area / c.area;
    s.density_min = std::min(s.density_min, d);
    s.density_max = std::max(s.density_max, d);
  }
  if (s.density_max == 0) s.density_min = 0;
  s.coverage = texels.empty() ? 0 : double(all) / double(texels.size());
  return s;
}

DirectionFrame direction_frame(const Chart& c) {
  if (c.kind == ChartKind::sphere || c.from_lightmap) return {};
  // The tangent from the normal alone, so that charts in one plane (two meshes of a floor, a
  // seam's two sides) lay their maps alike; a fixed axis picked with a margin, so that rounding
  // in a normal never turns it.
  const Vec3 e = std::abs(c.n.z) > 0.9f ? Vec3{1, 0, 0} : Vec3{0, 0, 1};
  const Vec3 y = normalize(cross(e, c.n));
  return {c.n, y, cross(c.n, y)};
}

}  // namespace penumbra::spaceland::atlas
