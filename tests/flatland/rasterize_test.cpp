// Rasterising scenes: coverage areas against closed forms, blending, layers, the default scene.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
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
