// Rasterising scenes: coverage areas against closed forms, the polygon fill against the
// brute-force test it replaced, blending, layers, the default scene.
#include "flatland/scene/rasterize.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <variant>
#include <vector>

#include "core/math.hpp"
#include "penumbra/flatland/scene.hpp"

namespace penumbra::flatland {
namespace {

SceneDesc grid(int w, int h) {
  SceneDesc d;
  d.width = w;
  d.height = h;
  return d;
}

Scene build_ok(const SceneDesc& d) {
  auto r = build_scene(d);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? *r : Scene{};
}

// Sum of opacity over all cells divided by the material's opacity: the area of a shape drawn on
// an empty grid. Semi-transparent materials blend linearly by coverage (opaque edges are
// sharpened, see OpaqueEdgesKeepTheSilhouette in flatland_trace_test.cpp).
double drawn_area(int w, int h, Shape shape) {
  SceneDesc d = grid(w, h);
  shape.material.opacity = 0.5f;
  d.shapes.push_back(std::move(shape));
  Scene s = build_ok(d);
  double sum = 0;
  for (float a : s.opacity) sum += a;
  return sum / 0.5;
}

Shape opaque(decltype(Shape::geometry) g) {
  return {std::move(g), Material{}};
}

double shoelace(const std::vector<std::array<float, 2>>& p) {
  double a = 0;
  for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
    a += double(p[j][0]) * p[i][1] - double(p[i][0]) * p[j][1];
  return std::fabs(a) / 2;
}

TEST(Rasterize, CircleArea) {
  for (double r : {5.3, 20.0}) {
    double area = drawn_area(64, 64, opaque(Circle{{32.37f, 31.71f}, float(r)}));
    EXPECT_NEAR(area, kPi * r * r, 0.005 * kPi * r * r) << "r = " << r;
  }
}

TEST(Rasterize, RotatedBoxArea) {
  double area = drawn_area(80, 80, opaque(Box{{40.3f, 39.8f}, {30, 12}, 30}));
  EXPECT_NEAR(area, 360.0, 0.005 * 360.0);
}

TEST(Rasterize, CapsuleArea) {
  std::array<float, 2> a{12.3f, 15.1f}, b{52.7f, 40.2f};
  float w = 6.5f;
  double len = std::hypot(double(b[0]) - a[0], double(b[1]) - a[1]);
  double expected = kPi * (w / 2.0) * (w / 2.0) + w * len;
  double area = drawn_area(64, 64, opaque(Segment{a, b, w}));
  EXPECT_NEAR(area, expected, 0.005 * expected);
}

TEST(Rasterize, TriangleArea) {
  std::vector<std::array<float, 2>> pts = {{5.2f, 4.1f}, {50.7f, 10.3f}, {20.4f, 55.9f}};
  double expected = shoelace(pts);
  EXPECT_NEAR(drawn_area(64, 64, opaque(Polygon{pts})), expected, 0.005 * expected);
}

TEST(Rasterize, ConcavePolygonArea) {
  std::vector<std::array<float, 2>> pts = {
      {10.2f, 10.1f}, {50.3f, 10.6f}, {50.1f, 50.4f}, {30.2f, 25.5f}, {10.4f, 50.2f}};
  double expected = shoelace(pts);
  EXPECT_NEAR(drawn_area(64, 64, opaque(Polygon{pts})), expected, 0.005 * expected);
}

// The brute-force polygon coverage the scanline fill replaced, kept as the reference it must
// match exactly: every cell's signed distance to every edge, then 16x16 samples, each tested
// against every edge, in cells within sqrt(2)/2 of the boundary.
namespace brute {

using Points = std::vector<std::array<float, 2>>;

double segment_distance(double px, double py, double ax, double ay, double bx, double by) {
  double dx = bx - ax, dy = by - ay;
  double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? std::clamp(((px - ax) * dx + (py - ay) * dy) / len2, 0.0, 1.0) : 0.0;
  double ex = px - ax - t * dx, ey = py - ay - t * dy;
  return std::sqrt(ex * ex + ey * ey);
}

bool inside(const Points& pts, double x, double y) {
  bool in = false;
  const std::size_t n = pts.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    double xi = pts[i][0], yi = pts[i][1], xj = pts[j][0], yj = pts[j][1];
    if ((yi > y) != (yj > y) && x < xj + (y - yj) * (xi - xj) / (yi - yj)) in = !in;
  }
  return in;
}

double distance(const Points& pts, double x, double y) {
  double d = std::numeric_limits<double>::infinity();
  const std::size_t n = pts.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++)
    d = std::min(d, segment_distance(x, y, pts[j][0], pts[j][1], pts[i][0], pts[i][1]));
  return inside(pts, x, y) ? -d : d;
}

// The old per-cell coverage of any shape with a signed distance and an exact inside test.
template <class G>
float cell_coverage(const G& g, int i, int j) {
  const double half_diagonal = 0.70710678118654752440;
  const double d = g.distance(i + 0.5, j + 0.5);
  if (d <= -half_diagonal) return 1;
  if (d >= half_diagonal) return 0;
  int hits = 0;
  for (int sy = 0; sy < 16; ++sy) {
    double y = j + (sy + 0.5) / 16;
    for (int sx = 0; sx < 16; ++sx) hits += g.inside(i + (sx + 0.5) / 16, y);
  }
  return float(hits) / float(16 * 16);
}

// Cells [i0, i1) x [j0, j1) touched by bounds {x0, y0, x1, y1}, clipped to the grid.
std::array<int, 4> cell_range(const std::array<double, 4>& b, int w, int h) {
  return {int(std::clamp(std::floor(b[0]), 0.0, double(w))),
          int(std::clamp(std::ceil(b[2]), 0.0, double(w))),
          int(std::clamp(std::floor(b[1]), 0.0, double(h))),
          int(std::clamp(std::ceil(b[3]), 0.0, double(h)))};
}

struct Polygon {
  const Points& pts;
  double distance(double x, double y) const { return brute::distance(pts, x, y); }
  bool inside(double x, double y) const { return brute::inside(pts, x, y); }
  std::array<double, 4> bounds() const {
    std::array<double, 4> b = {pts[0][0], pts[0][1], pts[0][0], pts[0][1]};
    for (const auto& p : pts) {
      b[0] = std::min(b[0], double(p[0]));
      b[1] = std::min(b[1], double(p[1]));
      b[2] = std::max(b[2], double(p[0]));
      b[3] = std::max(b[3], double(p[1]));
    }
    return b;
  }
};

std::vector<float> coverage(const Points& pts, int w, int h) {
  const Polygon g{pts};
  const auto [i0, i1, j0, j1] = cell_range(g.bounds(), w, h);
  std::vector<float> cov(std::size_t(w) * h, 0.0f);
  for (int j = j0; j < j1; ++j)
    for (int i = i0; i < i1; ++i) cov[std::size_t(j) * w + i] = cell_coverage(g, i, j);
  return cov;
}

}  // namespace brute

// The other shapes as they were drawn before runs and sample rows: each cell alone, each of an
// edge cell's 16x16 samples tested.
struct BruteDisk {
  double cx, cy, r;
  double distance(double x, double y) const { return std::hypot(x - cx, y - cy) - r; }
  bool inside(double x, double y) const {
    double dx = x - cx, dy = y - cy;
    return dx * dx + dy * dy < r * r;
  }
  std::array<double, 4> bounds() const { return {cx - r, cy - r, cx + r, cy + r}; }
};

struct BruteBox {
  double cx, cy, hw, hh, cs, sn;
  void local(double x, double y, double& u, double& v) const {
    double dx = x - cx, dy = y - cy;
    u = dx * cs + dy * sn;
    v = -dx * sn + dy * cs;
  }
  double distance(double x, double y) const {
    double u, v;
    local(x, y, u, v);
    double qx = std::fabs(u) - hw, qy = std::fabs(v) - hh;
    return std::sqrt(std::max(qx, 0.0) * std::max(qx, 0.0) +
                     std::max(qy, 0.0) * std::max(qy, 0.0)) +
           std::min(std::max(qx, qy), 0.0);
  }
  bool inside(double x, double y) const {
    double u, v;
    local(x, y, u, v);
    return std::fabs(u) < hw && std::fabs(v) < hh;
  }
  std::array<double, 4> bounds() const {
    double ex = std::fabs(cs) * hw + std::fabs(sn) * hh;
    double ey = std::fabs(sn) * hw + std::fabs(cs) * hh;
    return {cx - ex, cy - ey, cx + ex, cy + ey};
  }
};

struct BruteCapsule {
  double ax, ay, bx, by, r;
  double distance(double x, double y) const {
    return brute::segment_distance(x, y, ax, ay, bx, by) - r;
  }
  bool inside(double x, double y) const {
    return brute::segment_distance(x, y, ax, ay, bx, by) < r;
  }
  std::array<double, 4> bounds() const {
    return {std::min(ax, bx) - r, std::min(ay, by) - r, std::max(ax, bx) + r, std::max(ay, by) + r};
  }
};

// Blends shape g over s as build_scene did, cell by cell.
template <class G>
void brute_draw(Scene& s, const G& g, const Material& m) {
  const auto [i0, i1, j0, j1] = brute::cell_range(g.bounds(), s.width, s.height);
  for (int j = j0; j < j1; ++j)
    for (int i = i0; i < i1; ++i)
      if (const float c = brute::cell_coverage(g, i, j); c > 0)
        blend(s, s.index(i, j), blend_fraction(c, m), m);
}

void brute_draw(Scene& s, const Shape& shape) {
  const Material& m = shape.material;
  if (const auto* c = std::get_if<Circle>(&shape.geometry)) {
    brute_draw(s, BruteDisk{c->center[0], c->center[1], c->radius}, m);
  } else if (const auto* b = std::get_if<Box>(&shape.geometry)) {
    const double a = double(b->angle) * (kPi / 180.0);
    brute_draw(s,
               BruteBox{b->center[0], b->center[1], b->size[0] / 2.0, b->size[1] / 2.0, std::cos(a),
                        std::sin(a)},
               m);
  } else if (const auto* g = std::get_if<Segment>(&shape.geometry)) {
    brute_draw(s, BruteCapsule{g->a[0], g->a[1], g->b[0], g->b[1], g->width / 2.0}, m);
  } else if (const auto* p = std::get_if<Polygon>(&shape.geometry)) {
    brute_draw(s, brute::Polygon{p->points}, m);
  }
}

// Expects build_scene to give the scene that drawing its shapes one by one, cell by cell, gives.
void expect_scene_matches_brute_force(const SceneDesc& d, const std::string& what) {
  const Scene s = build_ok(d);
  SceneDesc bare = d;
  bare.shapes.clear();
  Scene want = build_ok(bare);
  for (const Shape& shape : d.shapes) brute_draw(want, shape);
  EXPECT_EQ(s.opacity, want.opacity) << what;
  EXPECT_EQ(s.emission, want.emission) << what;
  EXPECT_EQ(s.albedo, want.albedo) << what;
}

// Expects the fill's coverage to equal the brute-force one in every cell.
void expect_matches_brute_force(const brute::Points& pts, int w, int h, const std::string& what) {
  const std::vector<float> want = brute::coverage(pts, w, h);
  const std::vector<float> got = polygon_coverage(Polygon{pts}, w, h);
  ASSERT_EQ(got.size(), want.size());
  int wrong = 0;
  for (std::size_t k = 0; k < got.size(); ++k) {
    if (got[k] == want[k]) continue;
    if (++wrong <= 3)
      ADD_FAILURE() << what << ": cell (" << k % w << ", " << k / w << ") has " << got[k]
                    << ", brute force " << want[k];
  }
  EXPECT_EQ(wrong, 0) << what;
}

brute::Points random_points(std::mt19937& rng, int n, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  brute::Points pts(n);
  for (auto& p : pts) p = {float(u(rng)), float(u(rng))};
  return pts;
}

TEST(Rasterize, PolygonFillMatchesBruteForceOnRandomPolygons) {
  std::mt19937 rng(16);
  for (int k = 0; k < 40; ++k) {
    // Self-crossing in general; some reach past the grid on every side.
    const int n = 3 + k % 13 * 3;
    expect_matches_brute_force(random_points(rng, n, -8, 56), 48, 40,
                               "random " + std::to_string(k));
  }
  // Many edges: every cell is an edge cell and rows hold dozens of crossings.
  expect_matches_brute_force(random_points(rng, 400, -2, 34), 32, 32, "400 points");
}

TEST(Rasterize, PolygonFillMatchesBruteForceOnLatticePoints) {
  // Points on the 1/32 lattice of sample positions and cell centres, so that crossings and
  // vertices fall exactly on samples, centres and cell borders, and edges run along sample rows.
  std::mt19937 rng(32);
  std::uniform_int_distribution<int> u(-32, 24 * 32);
  for (int k = 0; k < 30; ++k) {
    brute::Points pts(3 + k % 7);
    for (auto& p : pts) p = {u(rng) / 32.0f, u(rng) / 32.0f};
    expect_matches_brute_force(pts, 24, 20, "lattice " + std::to_string(k));
  }
  // Whole and half cells: edges through cell centres and along cell borders.
  std::uniform_int_distribution<int> v(-2, 40);
  for (int k = 0; k < 30; ++k) {
    brute::Points pts(3 + k % 5);
    for (auto& p : pts) p = {v(rng) / 2.0f, v(rng) / 2.0f};
    expect_matches_brute_force(pts, 20, 20, "half cells " + std::to_string(k));
  }
}

TEST(Rasterize, PolygonFillMatchesBruteForceOnDegenerateEdges) {
  const std::vector<std::pair<std::string, brute::Points>> cases = {
      {"horizontal edges",
       {{2.3f, 5.5f}, {20.7f, 5.5f}, {20.7f, 14.0f}, {8.1f, 14.0f}, {8.1f, 9.5f}}},
      {"repeated points",
       {{3.2f, 3.1f}, {3.2f, 3.1f}, {18.4f, 6.6f}, {18.4f, 6.6f}, {9.9f, 17.2f}}},
      {"collinear", {{2.5f, 2.5f}, {10.5f, 10.5f}, {18.5f, 18.5f}}},
      {"all one point", {{7.3f, 8.4f}, {7.3f, 8.4f}, {7.3f, 8.4f}}},
      {"spike", {{4.1f, 4.2f}, {16.3f, 10.1f}, {4.1f, 4.2f}, {6.2f, 15.5f}}},
      {"edge back and forth", {{2.0f, 2.0f}, {18.0f, 9.0f}, {2.0f, 2.0f}, {18.0f, 9.0f}}},
      {"tiny", {{10.31f, 10.42f}, {10.39f, 10.44f}, {10.35f, 10.49f}}},
      {"thinner than a sample", {{1.1f, 7.51f}, {19.2f, 7.52f}, {19.2f, 7.53f}, {1.1f, 7.54f}}},
      {"vertical sliver", {{9.5f, 1.2f}, {9.5001f, 1.2f}, {9.5001f, 18.7f}, {9.5f, 18.7f}}},
  };
  for (const auto& [what, pts] : cases) expect_matches_brute_force(pts, 20, 20, what);
}

TEST(Rasterize, PolygonFillMatchesBruteForceOnHugeAndOutsidePolygons) {
  // Far larger than the grid: edges cross it with extreme slopes, some cells are inside.
  expect_matches_brute_force({{-1e6f, -3e5f}, {2e6f, 17.3f}, {-4e5f, 1e6f}}, 32, 24, "huge");
  expect_matches_brute_force({{-1e30f, 5.2f}, {1e30f, 9.7f}, {3e29f, -1e30f}}, 32, 24, "1e30");
  expect_matches_brute_force(
      {{-50.5f, -40.2f}, {90.3f, -35.1f}, {85.2f, 70.8f}, {15.7f, 12.3f}, {-45.1f, 66.6f}}, 32, 24,
      "around the grid");
  // Beside the grid: covers nothing, though its box may overlap the grid.
  expect_matches_brute_force({{-9.2f, 3.1f}, {-0.8f, 5.5f}, {-4.4f, 30.2f}}, 32, 24, "left");
  expect_matches_brute_force({{35.2f, -3.1f}, {60.8f, 5.5f}, {-40.4f, -0.2f}}, 32, 24, "above");
  expect_matches_brute_force({{1.5f, 1.5f}, {1e7f, 2.5f}, {2.5f, 1e7f}}, 32, 24, "long thin");
}

TEST(Rasterize, PolygonFillIndependentOfThreadCount) {
  std::mt19937 rng(5);
  const Polygon p{random_points(rng, 3000, -4, 260)};
  const std::vector<float> many = polygon_coverage(p, 256, 256);
  std::vector<float> one;
  tbb::task_arena(1).execute([&] { one = polygon_coverage(p, 256, 256); });
  EXPECT_EQ(one, many);
}

TEST(Rasterize, PolygonWorkIsCellsPlusEdgesTimesRows) {
  // 100k points across a 64^2 grid: every cell is an edge cell. The brute-force test did
  // cells x points x (2 + 256) edge tests here, minutes of work.
  const int n = 100000, side = 64;
  std::mt19937 rng(100);
  const Polygon p{random_points(rng, n, -2, side + 2)};
  PolygonWork work;
  const std::vector<float> cov = polygon_coverage(p, side, side, &work);

  // The cost law: per edge, its rows (17 crossing rows each: 16 of samples, 1 of centres) and
  // the cells within sqrt(2)/2 of it; per cell, 17 row sweeps.
  double edge_rows = 0, edge_cells = 0;
  for (std::size_t i = 0, j = n - 1; i < std::size_t(n); j = i++) {
    const auto &a = p.points[i], &b = p.points[j];
    const double rows = std::fabs(double(a[1]) - b[1]) + 3;
    edge_rows += std::min(rows, double(side));
    edge_cells += 6 * (std::fabs(double(a[0]) - b[0]) + rows);
  }
  const double cells = double(side) * side;
  EXPECT_LE(work.crossing_tests, 17 * edge_rows);
  EXPECT_LE(work.distance_tests, edge_cells);
  EXPECT_LE(work.cell_visits, 17 * cells);
  EXPECT_LE(work.edge_visits, 32.0 * n + edge_rows);
  const double total =
      double(work.crossing_tests + work.distance_tests + work.cell_visits + work.edge_visits);
  EXPECT_LT(total * 4, cells * n);
  // It did the work: every cell is partly covered.
  for (float c : cov) EXPECT_TRUE(c > 0 && c < 1);
}

TEST(Rasterize, RegularPolygonAreaIsAnalytic) {
  for (int n : {5, 12, 1000}) {
    const double r = 21.3, cx = 32.37, cy = 30.81;
    std::vector<std::array<float, 2>> pts;
    for (int k = 0; k < n; ++k) {
      const double t = 2 * kPi * k / n + 0.1;
      pts.push_back({float(cx + r * std::cos(t)), float(cy + r * std::sin(t))});
    }
    const double area = n / 2.0 * r * r * std::sin(2 * kPi / n);
    double sum = 0;
    for (float c : polygon_coverage(Polygon{pts}, 64, 64)) sum += c;
    EXPECT_NEAR(sum, area, 1e-3 * area) << n << " sides";
  }
}

TEST(Rasterize, SceneDrawsPolygonsWithTheirCoverage) {
  // Polygons over a layer and a box: each cell blends the material by the brute-force coverage.
  SceneDesc d = grid(40, 32);
  d.layers.opacity = std::vector<float>(40 * 32, 0.25f);
  d.shapes.push_back({Box{{20, 16}, {30, 20}, 10}, Material{{1, 0, 0}, 0.5f, {0.3f, 0.3f, 0.3f}}});
  const brute::Points star = {
      {20.2f, 1.3f}, {27.1f, 28.8f}, {3.4f, 11.7f}, {36.6f, 11.2f}, {12.9f, 29.4f}};
  const brute::Points outside = {{-10.3f, 20.1f}, {15.2f, 25.6f}, {8.8f, 45.3f}};
  const Material glow{{2, 3, 4}, 1, {0.1f, 0.2f, 0.3f}}, fog{{}, 0.3f, {0.5f, 0.5f, 0.5f}};
  d.shapes.push_back({Polygon{star}, glow});
  d.shapes.push_back({Polygon{outside}, fog});
  const Scene s = build_ok(d);

  SceneDesc base = d;
  base.shapes.resize(1);
  Scene want = build_ok(base);
  for (const auto& [pts, m] : {std::pair{star, glow}, std::pair{outside, fog}}) {
    const std::vector<float> cov = brute::coverage(pts, 40, 32);
    for (std::size_t k = 0; k < cov.size(); ++k)
      if (cov[k] > 0) blend(want, k, blend_fraction(cov[k], m), m);
  }
  EXPECT_EQ(s.opacity, want.opacity);
  EXPECT_EQ(s.emission, want.emission);
  EXPECT_EQ(s.albedo, want.albedo);
}

TEST(Rasterize, CirclesMatchBruteForce) {
  // Centres and radii anywhere, on the sample lattice (samples exactly on the circle), tiny,
  // huge and mostly outside; each alone on a grid so that every cell's coverage is compared.
  std::mt19937 rng(300);
  std::uniform_real_distribution<double> u(-6, 46), radius(0.01, 14);
  std::uniform_int_distribution<int> lattice(-64, 40 * 32), lattice_radius(1, 320);
  std::vector<Circle> circles;
  for (int k = 0; k < 60; ++k)
    circles.push_back({{float(u(rng)), float(u(rng))}, float(radius(rng))});
  for (int k = 0; k < 60; ++k)
    circles.push_back({{lattice(rng) / 32.0f, lattice(rng) / 32.0f}, lattice_radius(rng) / 32.0f});
  circles.push_back({{20.25f, 17.5f}, 0.001f});
  circles.push_back({{20.0f, 17.0f}, 0.5f});
  circles.push_back({{-1e5f, 16.3f}, 1e5f + 21.7f});
  circles.push_back({{16.1f, 1e6f}, 1e6f - 15.2f});
  for (std::size_t k = 0; k < circles.size(); ++k) {
    SceneDesc d = grid(40, 33);
    d.shapes.push_back({circles[k], Material{{}, 0.5f, {}}});
    expect_scene_matches_brute_force(d, "circle " + std::to_string(k));
  }
}

TEST(Rasterize, ManyShapesMatchBruteForceInOrder) {
  // Overlapping circles, boxes and segments of every size with polygons between them: each cell
  // must take the shapes in scene order, whichever band of rows draws them.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-10, 110), size(0.2, 30), unit(0, 1);
  SceneDesc d = grid(100, 90);
  for (int k = 0; k < 400; ++k) {
    const Material m{{float(4 * unit(rng)), 0, float(unit(rng))},
                     k % 3 ? float(unit(rng)) : 1.0f,
                     {float(unit(rng)), 0.5f, 0}};
    const std::array<float, 2> c{float(pos(rng)), float(pos(rng))};
    const float sz = float(size(rng) * (k % 10 ? 0.2 : 1));
    switch (k % 4) {
      case 0:
        d.shapes.push_back({Circle{c, sz}, m});
        break;
      case 1:
        d.shapes.push_back({Box{c, {sz, float(size(rng))}, float(360 * unit(rng))}, m});
        break;
      case 2:
        d.shapes.push_back({Segment{c, {float(pos(rng)), float(pos(rng))}, sz}, m});
        break;
      default:
        d.shapes.push_back({Circle{c, sz * 0.1f}, m});
        break;
    }
    if (k % 97 == 0) d.shapes.push_back({Polygon{random_points(rng, 6, -5, 105)}, m});
  }
  expect_scene_matches_brute_force(d, "mixed shapes with polygons between them");
}

TEST(Rasterize, PolygonUsesEvenOddRule) {
  // A pentagram: its inner pentagon is crossed twice, so it is outside under even-odd.
  std::vector<std::array<float, 2>> pts;
  for (int k = 0; k < 5; ++k) {
    double t = (-90.0 + 144.0 * k) * kPi / 180.0;
    pts.push_back({float(32 + 25 * std::cos(t)), float(32 + 25 * std::sin(t))});
  }
  SceneDesc d = grid(64, 64);
  d.shapes.push_back(opaque(Polygon{pts}));
  Scene s = build_ok(d);
  EXPECT_EQ(s.opacity[s.index(31, 31)], 0.0f);  // centre
  EXPECT_EQ(s.opacity[s.index(31, 12)], 1.0f);  // in the top point
}

TEST(Rasterize, CellsCoverUnitSquares) {
  // A unit box centred on (2.5, 1.5) covers exactly cell (2, 1).
  SceneDesc d = grid(5, 4);
  d.shapes.push_back(opaque(Box{{2.5f, 1.5f}, {1, 1}, 0}));
  Scene s = build_ok(d);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 5; ++x)
      EXPECT_EQ(s.opacity[s.index(x, y)], (x == 2 && y == 1) ? 1.0f : 0.0f) << x << "," << y;
}

TEST(Rasterize, BoxAngleTurnsFromXTowardsY) {
  SceneDesc d = grid(64, 64);
  d.shapes.push_back(opaque(Box{{32, 32}, {40, 2}, 30}));
  Scene s = build_ok(d);
  double c = std::cos(kPi / 6), sn = std::sin(kPi / 6);
  auto at = [&](double x, double y) { return s.opacity[s.index(int(x), int(y))]; };
  // y grows down, so +30 degrees points right and down.
  EXPECT_EQ(at(32 + 15 * c, 32 + 15 * sn), 1.0f);
  EXPECT_EQ(at(32 + 15 * c, 32 - 15 * sn), 0.0f);
}

TEST(Rasterize, ClipsShapesToTheGrid) {
  // Half a disk lies outside: the drawn area is the half inside.
  double area = drawn_area(40, 40, opaque(Circle{{0, 20.3f}, 12}));
  EXPECT_NEAR(area, kPi * 144 / 2, 0.005 * kPi * 144 / 2);
  // Entirely outside, including far away: nothing drawn.
  EXPECT_EQ(drawn_area(40, 40, opaque(Circle{{-100, 20}, 12})), 0.0);
  EXPECT_EQ(drawn_area(40, 40, opaque(Circle{{1e30f, -1e30f}, 5})), 0.0);
}

TEST(Rasterize, LaterShapeReplacesEarlierInCoveredCells) {
  SceneDesc d = grid(40, 40);
  d.shapes.push_back({Box{{20, 20}, {40, 40}, 0}, Material{{1, 2, 3}, 1, {0.5f, 0.5f, 0.5f}}});
  d.shapes.push_back({Circle{{20, 20}, 8}, Material{{5, 0, 0.25f}, 0.3f, {0.1f, 0.2f, 0.3f}}});
  Scene s = build_ok(d);
  const std::size_t in = s.index(20, 20), out = s.index(2, 2);
  EXPECT_EQ(s.opacity[in], 0.3f);
  EXPECT_EQ(s.emission[in * 3 + 0], 5.0f);
  EXPECT_EQ(s.emission[in * 3 + 1], 0.0f);
  EXPECT_EQ(s.emission[in * 3 + 2], 0.25f);
  EXPECT_EQ(s.albedo[in * 3 + 0], 0.1f);
  EXPECT_EQ(s.albedo[in * 3 + 1], 0.2f);
  EXPECT_EQ(s.albedo[in * 3 + 2], 0.3f);
  EXPECT_EQ(s.opacity[out], 1.0f);
  EXPECT_EQ(s.emission[out * 3 + 1], 2.0f);
  EXPECT_EQ(s.albedo[out * 3 + 2], 0.5f);
}

// Fraction of cell (i, j) inside the disk, by a fine 512x512 grid of samples.
double disk_fraction(double cx, double cy, double r, int i, int j) {
  const int n = 512;
  int hits = 0;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      double x = i + (a + 0.5) / n - cx, y = j + (b + 0.5) / n - cy;
      hits += x * x + y * y < r * r;
    }
  return double(hits) / (double(n) * n);
}

TEST(Rasterize, OpaqueEmitterEdgeCellKeepsEmissionWithSharpenedCoverage) {
  const float cx = 16.3f, cy = 15.8f, r = 6.4f;
  SceneDesc d = grid(32, 32);
  d.shapes.push_back({Circle{{cx, cy}, r}, Material{{4, 3, 2}, 1, {0.2f, 0.4f, 0.6f}}});
  Scene s = build_ok(d);
  int edge_cells = 0;
  for (int j = 0; j < 32; ++j) {
    for (int i = 0; i < 32; ++i) {
      const std::size_t k = s.index(i, j);
      const float a = s.opacity[k];
      if (a <= 0 || a >= 1) continue;
      ++edge_cells;
      EXPECT_NEAR(s.emission[k * 3 + 0], 4, 1e-5);
      EXPECT_NEAR(s.emission[k * 3 + 1], 3, 1e-5);
      EXPECT_NEAR(s.emission[k * 3 + 2], 2, 1e-5);
      EXPECT_NEAR(s.albedo[k * 3 + 1], 0.4, 1e-6);
      if (edge_cells % 5 == 0) {  // the fine reference is slow; a sample of cells is enough
        EXPECT_NEAR(a, std::pow(disk_fraction(cx, cy, r, i, j), 4.0), 0.03) << i << "," << j;
      }
    }
  }
  EXPECT_GT(edge_cells, 20);
  // Cells outside the disk stay empty and emit nothing.
  EXPECT_EQ(s.opacity[s.index(0, 0)], 0.0f);
  EXPECT_EQ(s.emission[s.index(0, 0) * 3], 0.0f);
}

TEST(Rasterize, EdgeCellsBlendPremultipliedByOpacity) {
  const Circle disk{{16.3f, 15.8f}, 6.4f};
  // Coverage per cell, from the disk alone on an empty grid.
  SceneDesc alone = grid(32, 32);
  alone.shapes.push_back({disk, Material{{}, 0.5f, {}}});
  Scene cov = build_ok(alone);
  for (float& a : cov.opacity) a /= 0.5f;

  SceneDesc d = grid(32, 32);
  d.shapes.push_back({Box{{16, 16}, {32, 32}, 0}, Material{{2, 0, 0}, 0.5f, {0.8f, 0, 0}}});
  d.shapes.push_back({disk, Material{{0, 4, 0}, 0.25f, {0, 0.6f, 0}}});
  Scene s = build_ok(d);
  int checked = 0;
  for (std::size_t k = 0; k < s.cells(); ++k) {
    const double c = cov.opacity[k];
    if (c <= 0 || c >= 1) continue;
    ++checked;
    const double w1 = c * 0.25, w0 = (1 - c) * 0.5, a = w1 + w0;
    EXPECT_NEAR(s.opacity[k], a, 1e-6);
    EXPECT_NEAR(s.emission[k * 3 + 0], w0 * 2 / a, 1e-5);
    EXPECT_NEAR(s.emission[k * 3 + 1], w1 * 4 / a, 1e-5);
    EXPECT_NEAR(s.albedo[k * 3 + 0], w0 * 0.8 / a, 1e-6);
    EXPECT_NEAR(s.albedo[k * 3 + 1], w1 * 0.6 / a, 1e-6);
  }
  EXPECT_GT(checked, 20);
}

TEST(Rasterize, WithoutOpacityLayerEmittersAreOpaque) {
  SceneDesc d = grid(4, 3);
  ImageRgb e(4, 3);
  e.set(1, 1, {0, 0, 2});
  e.set(2, 0, {0.5f, 0, 0});
  d.layers.emission = e;
  ImageRgb albedo(4, 3);
  albedo.set(3, 2, {0.5f, 0.5f, 0.5f});
  d.layers.albedo = albedo;
  d.shapes.push_back({Box{{0.5f, 2.5f}, {1, 1}, 0}, Material{{}, 0.4f, {}}});
  Scene s = build_ok(d);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 4; ++x) {
      float want = (x == 1 && y == 1) || (x == 2 && y == 0) ? 1.0f : 0.0f;
      if (x == 0 && y == 2) want = 0.4f;  // the shape drawn on top
      EXPECT_EQ(s.opacity[s.index(x, y)], want) << x << "," << y;
    }
  }
  EXPECT_EQ(s.emission[s.index(1, 1) * 3 + 2], 2.0f);
  EXPECT_EQ(s.albedo[s.index(3, 2) * 3 + 1], 0.5f);
}

TEST(Rasterize, OpacityLayerIsUsedAsIs) {
  SceneDesc d = grid(3, 2);
  d.layers.opacity = std::vector<float>{0, 0.1f, 0.2f, 0.3f, 0.4f, 1};
  ImageRgb e(3, 2);
  e.set(0, 0, {1, 1, 1});
  d.layers.emission = e;
  Scene s = build_ok(d);
  EXPECT_EQ(s.opacity, *d.layers.opacity);
  EXPECT_EQ(s.emission[0], 1.0f);
}

TEST(Rasterize, RejectsInvalidScenes) {
  SceneDesc d = grid(8, 8);
  d.source = "code";
  d.shapes.push_back(opaque(Circle{{2, 2}, -2}));
  auto r = build_scene(d);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, "code: shapes[0].radius: expected a number > 0, found -2");
}

TEST(Rasterize, IndependentOfThreadCount) {
  SceneDesc d = default_scene();
  Scene many = build_ok(d);
  Scene one;
  tbb::task_arena(1).execute([&] { one = build_ok(d); });
  EXPECT_EQ(one.opacity, many.opacity);
  EXPECT_EQ(one.emission, many.emission);
  EXPECT_EQ(one.albedo, many.albedo);
}

TEST(Rasterize, DefaultSceneBuilds) {
  SceneDesc d = default_scene();
  EXPECT_EQ(d.source, "<default scene>");
  EXPECT_TRUE(validate(d).ok());
  Scene s = build_ok(d);
  ASSERT_EQ(s.width, 512);
  ASSERT_EQ(s.height, 384);
  EXPECT_GT(s.environment.b, 0.0f);
  int emitters = 0, walls = 0, fog = 0, reflective = 0;
  for (std::size_t k = 0; k < s.cells(); ++k) {
    const float* e = &s.emission[k * 3];
    const bool emits = e[0] + e[1] + e[2] > 0;
    emitters += emits && s.opacity[k] == 1.0f;
    walls += !emits && s.opacity[k] == 1.0f;
    fog += std::fabs(s.opacity[k] - 0.05f) < 1e-6f;
    reflective += s.albedo[k * 3] >= 0.5f && s.opacity[k] == 1.0f;
  }
  EXPECT_GT(emitters, 3 * 100);  // three disks of radius >= 6
  EXPECT_GT(walls, 1000);
  EXPECT_GT(fog, 1000);
  EXPECT_GT(reflective, 1000);
}

}  // namespace
}  // namespace penumbra::flatland
