// Rasterising a SceneDesc into per-cell emission, opacity and albedo.
//
// Layers are copied first; shapes are then drawn in order with anti-aliased coverage. A cell is
// classified by the signed distance from its centre to the shape boundary: a cell lies within
// sqrt(2)/2 of its centre, so beyond that distance it is fully inside or outside, and only
// boundary cells are supersampled (16x16 points, exact inside tests).
#include "flatland/scene/rasterize.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <variant>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "penumbra/flatland/scene.hpp"

namespace penumbra::flatland {
namespace {

constexpr double kHalfDiagonal = 0.70710678118654752440;
constexpr int kSamples = 16;  // per axis, in boundary cells

struct Bounds {
  double x0, y0, x1, y1;
};

double length(double x, double y) {
  return std::sqrt(x * x + y * y);
}

// Distance from p to the segment a-b.
double segment_distance(double px, double py, double ax, double ay, double bx, double by) {
  double dx = bx - ax, dy = by - ay;
  double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? std::clamp(((px - ax) * dx + (py - ay) * dy) / len2, 0.0, 1.0) : 0.0;
  return length(px - ax - t * dx, py - ay - t * dy);
}

// Each geometry: signed distance (negative inside), exact inside test, bounding box.
struct DiskGeom {
  double cx, cy, r;
  explicit DiskGeom(const Circle& c) : cx(c.center[0]), cy(c.center[1]), r(c.radius) {}
  double distance(double x, double y) const { return length(x - cx, y - cy) - r; }
  bool inside(double x, double y) const {
    double dx = x - cx, dy = y - cy;
    return dx * dx + dy * dy < r * r;
  }
  Bounds bounds() const { return {cx - r, cy - r, cx + r, cy + r}; }
};

struct BoxGeom {
  double cx, cy, hw, hh, cs, sn;
  explicit BoxGeom(const Box& b)
      : cx(b.center[0]), cy(b.center[1]), hw(b.size[0] / 2.0), hh(b.size[1] / 2.0) {
    // The box's local x axis is (cos, sin) in y-down coordinates: +x turning towards +y.
    double a = double(b.angle) * (kPi / 180.0);
    cs = std::cos(a);
    sn = std::sin(a);
  }
  void local(double x, double y, double& u, double& v) const {
    double dx = x - cx, dy = y - cy;
    u = dx * cs + dy * sn;
    v = -dx * sn + dy * cs;
  }
  double distance(double x, double y) const {
    double u, v;
    local(x, y, u, v);
    double qx = std::fabs(u) - hw, qy = std::fabs(v) - hh;
    return length(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
  }
  bool inside(double x, double y) const {
    double u, v;
    local(x, y, u, v);
    return std::fabs(u) < hw && std::fabs(v) < hh;
  }
  Bounds bounds() const {
    double ex = std::fabs(cs) * hw + std::fabs(sn) * hh;
    double ey = std::fabs(sn) * hw + std::fabs(cs) * hh;
    return {cx - ex, cy - ey, cx + ex, cy + ey};
  }
};

struct CapsuleGeom {
  double ax, ay, bx, by, r;
  explicit CapsuleGeom(const Segment& s)
      : ax(s.a[0]), ay(s.a[1]), bx(s.b[0]), by(s.b[1]), r(s.width / 2.0) {}
  double distance(double x, double y) const { return segment_distance(x, y, ax, ay, bx, by) - r; }
  bool inside(double x, double y) const { return segment_distance(x, y, ax, ay, bx, by) < r; }
  Bounds bounds() const {
    return {std::min(ax, bx) - r, std::min(ay, by) - r, std::max(ax, bx) + r, std::max(ay, by) + r};
  }
};

struct PolygonGeom {
  const std::vector<std::array<float, 2>>& pts;
  explicit PolygonGeom(const Polygon& p) : pts(p.points) {}
  // Even-odd rule: count edge crossings of a ray towards +x.
  bool inside(double x, double y) const {
    bool in = false;
    const std::size_t n = pts.size();
    for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
      double xi = pts[i][0], yi = pts[i][1], xj = pts[j][0], yj = pts[j][1];
      if ((yi > y) != (yj > y) && x < xj + (y - yj) * (xi - xj) / (yi - yj)) in = !in;
    }
    return in;
  }
  double distance(double x, double y) const {
    double d = std::numeric_limits<double>::infinity();
    const std::size_t n = pts.size();
    for (std::size_t i = 0, j = n - 1; i < n; j = i++)
      d = std::min(d, segment_distance(x, y, pts[j][0], pts[j][1], pts[i][0], pts[i][1]));
    return inside(x, y) ? -d : d;
  }
  Bounds bounds() const {
    Bounds b{pts[0][0], pts[0][1], pts[0][0], pts[0][1]};
    for (const auto& p : pts) {
      b.x0 = std::min(b.x0, double(p[0]));
      b.y0 = std::min(b.y0, double(p[1]));
      b.x1 = std::max(b.x1, double(p[0]));
      b.y1 = std::max(b.y1, double(p[1]));
    }
    return b;
  }
};

// Fraction of cell (i, j) covered by the shape.
template <class Geom>
float coverage(const Geom& g, int i, int j) {
  double d = g.distance(i + 0.5, j + 0.5);
  if (d <= -kHalfDiagonal) return 1;
  if (d >= kHalfDiagonal) return 0;
  int hits = 0;
  for (int sy = 0; sy < kSamples; ++sy) {
    double y = j + (sy + 0.5) / kSamples;
    for (int sx = 0; sx < kSamples; ++sx) hits += g.inside(i + (sx + 0.5) / kSamples, y);
  }
  return float(hits) / float(kSamples * kSamples);
}

}  // namespace

// A ray grazing the edge of an opaque shape crosses several partly covered cells in a row and
// their opacities compound, so blending opaque coverage linearly makes a disk look up to half a
// cell wider than it is. Sharpening the coverage to c^4 keeps the silhouette of disks of radius 4
// to 30 within 0.16 cells of the true one (measured; see docs/scene-format.md). Materials that
// are not opaque blend linearly, which keeps their optical depth on average.
float opaque_edge(float c) {
  const float c2 = c * c;
  return c2 * c2;
}

// Premultiplied "over": the shape replaces the old values in the covered fraction c, with
// emission and albedo weighted by opacity so that a partly covered emitter cell emits like its
// covered part. c == 1 copies the material exactly.
void blend(Scene& s, std::size_t idx, float c, const Material& m) {
  float* le = &s.emission[idx * 3];
  float* rho = &s.albedo[idx * 3];
  const float le1[3] = {m.emission.r, m.emission.g, m.emission.b};
  const float rho1[3] = {m.albedo.r, m.albedo.g, m.albedo.b};
  if (c >= 1) {
    s.opacity[idx] = m.opacity;
    for (int k = 0; k < 3; ++k) {
      le[k] = le1[k];
      rho[k] = rho1[k];
    }
    return;
  }
  const float w1 = c * m.opacity, w0 = (1 - c) * s.opacity[idx];
  const float a = w1 + w0;
  s.opacity[idx] = a;
  for (int k = 0; k < 3; ++k) {
    le[k] = a > 0 ? (w1 * le1[k] + w0 * le[k]) / a : 0.0f;
    rho[k] = a > 0 ? (w1 * rho1[k] + w0 * rho[k]) / a : 0.0f;
  }
}

namespace {

// Cell index range [lo, hi) touched by the interval [a, b], clipped to [0, n).
void cell_range(double a, double b, int n, int& lo, int& hi) {
  lo = int(std::clamp(std::floor(a), 0.0, double(n)));
  hi = int(std::clamp(std::ceil(b), 0.0, double(n)));
}

template <class Geom>
void draw(Scene& s, const Geom& g, const Material& m) {
  const Bounds b = g.bounds();
  int i0, i1, j0, j1;
  cell_range(b.x0, b.x1, s.width, i0, i1);
  cell_range(b.y0, b.y1, s.height, j0, j1);
  if (i0 >= i1 || j0 >= j1) return;
  // Rows are independent and each cell is computed alone, so results do not depend on threads.
  parallel_for(j1 - j0, [&](int r) {
    const int j = j0 + r;
    for (int i = i0; i < i1; ++i) {
      const float c = coverage(g, i, j);
      if (c > 0) blend(s, s.index(i, j), blend_fraction(c, m), m);
    }
  });
}

}  // namespace

namespace {

Expected<Scene> build_scene_unchecked(const SceneDesc& desc) {
  if (Status st = validate(desc); !st) return st.error();

  Scene s;
  s.width = desc.width;
  s.height = desc.height;
  s.environment = desc.environment;
  const std::size_t n = s.cells();
  s.emission.assign(n * 3, 0.0f);
  s.albedo.assign(n * 3, 0.0f);
  s.opacity.assign(n, 0.0f);

  const Layers& layers = desc.layers;
  if (layers.emission) std::copy_n(layers.emission->data(), n * 3, s.emission.begin());
  if (layers.albedo) std::copy_n(layers.albedo->data(), n * 3, s.albedo.begin());
  if (layers.opacity) {
    std::copy_n(layers.opacity->data(), n, s.opacity.begin());
  } else {
    // Without an opacity layer, painted emitters are opaque and everything else is empty:
    // under the transport rule a cell of opacity 0 emits nothing, so an emission layer alone
    // would otherwise be invisible.
    for (std::size_t i = 0; i < n; ++i) {
      const float* e = &s.emission[i * 3];
      s.opacity[i] = (e[0] != 0 || e[1] != 0 || e[2] != 0) ? 1.0f : 0.0f;
    }
  }

  for (const Shape& shape : desc.shapes) {
    std::visit(
        [&](const auto& geom) {
          using T = std::decay_t<decltype(geom)>;
          if constexpr (std::is_same_v<T, Circle>) {
            draw(s, DiskGeom(geom), shape.material);
          } else if constexpr (std::is_same_v<T, Box>) {
            draw(s, BoxGeom(geom), shape.material);
          } else if constexpr (std::is_same_v<T, Segment>) {
            draw(s, CapsuleGeom(geom), shape.material);
          } else {
            draw(s, PolygonGeom(geom), shape.material);
          }
        },
        shape.geometry);
  }
  return s;
}

}  // namespace

Expected<Scene> build_scene(const SceneDesc& desc) {
  try {
    return build_scene_unchecked(desc);
  } catch (const std::bad_alloc&) {
    return Error{desc.source + ": out of memory while rasterising the scene"};
  } catch (const std::exception& e) {
    return Error{desc.source + ": " + e.what()};
  }
}

}  // namespace penumbra::flatland
