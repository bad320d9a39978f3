// OBJ faces of many corners (issue 37, item 7): triangulated in work linear in the corners where
// convex, covering the polygon exactly (the triangles' areas add up to the shoelace area, none is
// turned over), bounded where hostile.
#include "spaceland/scene/polygon.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace penumbra::spaceland {
namespace {

using Tris = std::vector<std::array<std::uint32_t, 3>>;

// Twice the signed area of triangle abc seen from +z.
double area2(Vec3 a, Vec3 b, Vec3 c) {
  return (double(b.x) - a.x) * (double(c.y) - a.y) - (double(b.y) - a.y) * (double(c.x) - a.x);
}

double shoelace2(const std::vector<Vec3>& p) {
  double s = 0;
  for (std::size_t i = 0; i < p.size(); ++i) s += area2({0, 0, 0}, p[i], p[(i + 1) % p.size()]);
  return s;
}

// The triangles cover a simple counter-clockwise polygon in the z = 0 plane exactly.
void expect_covers(const std::vector<Vec3>& p, const Tris& t) {
  ASSERT_EQ(t.size(), p.size() - 2);
  const double want = shoelace2(p);
  double sum = 0;
  std::size_t turned = 0;
  for (const auto& tri : t) {
    const double a = area2(p[tri[0]], p[tri[1]], p[tri[2]]);
    turned += a < -1e-9 * std::fabs(want);
    sum += a;
  }
  EXPECT_EQ(turned, 0u) << "triangles turned over";
  EXPECT_NEAR(sum, want, 1e-9 * std::fabs(want));
}

std::vector<Vec3> circle(std::size_t n, double r = 1) {
  std::vector<Vec3> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * double(i) / double(n);
    p[i] = {float(r * std::cos(a)), float(r * std::sin(a)), 0};
  }
  return p;
}

TEST(Polygon, ConvexFaceIsAFanInLinearWork) {
  for (std::size_t n : {5u, 100u, 100000u}) {
    const std::vector<Vec3> p = circle(n);
    Tris t;
    PolygonWork w;
    ASSERT_TRUE(triangulate_polygon(p, t, UINT64_MAX, w));
    EXPECT_TRUE(w.convex);
    EXPECT_LE(w.steps, 3 * n);  // tinyobjloader's clipping took 25 s at 100,000 corners
    expect_covers(p, t);
  }
}

// Faces a review found wrong (issue 37): a plate with a finely tessellated concave fillet and a C
// shape (each corner's turn back is below rounding, but the fan across them is turned over), and
// an L with a corner written twice (no turn, so the notch hid from the ears).
TEST(Polygon, FineConcaveArcsAndRepeatedCornersAreCoveredExactly) {
  std::vector<Vec3> plate = {{100, 50, 0}, {100, 100, 0}, {0, 100, 0}, {0, 0, 0}, {50, 0, 0}};
  for (int i = 0; i <= 400; ++i) {  // the notch's corner (50, 50), rounded by a radius of 5
    const double a = std::numbers::pi * (1 - 0.5 * i / 400.0);
    plate.push_back({float(55 + 5 * std::cos(a)), float(45 + 5 * std::sin(a)), 0});
  }
  std::vector<Vec3> c_shape;
  for (int i = 0; i <= 2000; ++i) {
    const double a = 5.236 * i / 2000;
    c_shape.push_back({float(std::cos(a)), float(std::sin(a)), 0});
  }
  for (int i = 2000; i >= 0; --i) {
    const double a = 5.236 * i / 2000;
    c_shape.push_back({float(0.5 * std::cos(a)), float(0.5 * std::sin(a)), 0});
  }
  for (const auto* face : {&plate, &c_shape}) {
    Tris t;
    PolygonWork w;
    ASSERT_TRUE(triangulate_polygon(*face, t, UINT64_MAX, w));
    EXPECT_FALSE(w.convex);
    expect_covers(*face, t);
  }
  const std::vector<Vec3> l = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0},
                               {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
  Tris t;
  PolygonWork w;
  ASSERT_TRUE(triangulate_polygon(l, t, UINT64_MAX, w));
  // The repeated corner has no area: 4 triangles for the 6 distinct corners, covering 3 units.
  ASSERT_EQ(t.size(), 4u);
  double sum = 0;
  for (const auto& tri : t) {
    const double a = area2(l[tri[0]], l[tri[1]], l[tri[2]]);
    EXPECT_GT(a, 0);
    sum += a;
  }
  EXPECT_DOUBLE_EQ(sum, 2 * 3.0);
}

// A quad is split along its shorter diagonal, as tinyobjloader split it, unless that turns a
// triangle over (a concave quad, which tinyobjloader got wrong).
TEST(Polygon, ConcaveQuadsTakeTheOtherDiagonal) {
  const std::vector<Vec3> dart = {{0, 0, 0}, {10, 1, 0}, {0, 2, 0}, {1, 1, 0}};
  Tris t;
  PolygonWork w;
  ASSERT_TRUE(triangulate_polygon(dart, t, 100, w));
  expect_covers(dart, t);
}

// A quad is split along its shorter diagonal, as tinyobjloader split it.
TEST(Polygon, QuadsSplitAlongTheShorterDiagonal) {
  Tris t;
  PolygonWork w;
  triangulate_polygon({{0, 0, 0}, {3, 0, 0}, {3, 1, 0}, {0, 1, 0}}, t, 100, w);
  EXPECT_EQ(t, (Tris{{0, 1, 3}, {1, 2, 3}}));  // 0-2 and 1-3 alike: the second
  t.clear();
  triangulate_polygon({{0, 0, 0}, {3, 0, 0}, {3, 1, 0}, {-1, 2, 0}}, t, 100, w);
  EXPECT_EQ(t, (Tris{{0, 1, 2}, {0, 2, 3}}));
}

// Star-shaped faces of random radii (simple, with many reflex corners), in every plane and both
// turning directions: covered exactly.
TEST(Polygon, NonConvexFacesAreCoveredExactly) {
  std::mt19937 rng(37);
  std::uniform_real_distribution<double> radius(0.2, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    const std::size_t n = 5 + std::size_t(trial) * 7;
    std::vector<Vec3> p = circle(n);
    for (Vec3& v : p) v = v * float(radius(rng));
    Tris t;
    PolygonWork w;
    ASSERT_TRUE(triangulate_polygon(p, t, UINT64_MAX, w));
    if (n > 20) {
      EXPECT_FALSE(w.convex);
    }
    expect_covers(p, t);
    // The same face in the x = 0 and y = 0 planes, clockwise: the same triangles.
    for (int plane = 0; plane < 2; ++plane) {
      std::vector<Vec3> q(p.rbegin(), p.rend());
      for (Vec3& v : q) v = plane == 0 ? Vec3{0, v.x, v.y} : Vec3{v.x, 0, v.y};
      Tris u;
      ASSERT_TRUE(triangulate_polygon(q, u, UINT64_MAX, w));
      std::vector<Vec3> back(q.size());
      for (std::size_t i = 0; i < q.size(); ++i)
        back[i] = plane == 0 ? Vec3{q[i].y, q[i].z, 0} : Vec3{q[i].x, q[i].z, 0};
      // Clockwise in the plane: covered with the orientation reversed.
      for (auto& tri : u) std::swap(tri[1], tri[2]);
      std::reverse(back.begin(), back.end());
      for (auto& tri : u)
        for (auto& i : tri) i = std::uint32_t(q.size() - 1 - i);
      expect_covers(back, u);
    }
  }
}

// A comb: half its corners reflex. Past the step limit nothing is appended; a face that crosses
// itself (a pentagram) still gets n - 2 triangles.
TEST(Polygon, HostileFacesAreBounded) {
  std::vector<Vec3> comb;
  const int teeth = 2000;
  for (int i = 0; i < teeth; ++i) {
    comb.push_back({float(2 * i), 0, 0});
    comb.push_back({float(2 * i + 1), 10, 0});
  }
  comb.push_back({float(2 * teeth), -5, 0});
  comb.push_back({0, -5, 0});
  Tris t;
  PolygonWork w;
  EXPECT_FALSE(triangulate_polygon(comb, t, 100000, w));
  EXPECT_TRUE(t.empty());
  EXPECT_GT(w.steps, 100000u);
  const std::vector<Vec3> star = {
      {0, 1, 0}, {0.59f, -0.81f, 0}, {-0.95f, 0.31f, 0}, {0.95f, 0.31f, 0}, {-0.59f, -0.81f, 0}};
  ASSERT_TRUE(triangulate_polygon(star, t, 1000, w));
  EXPECT_FALSE(w.convex);
  EXPECT_EQ(t.size(), 3u);
}

}  // namespace
}  // namespace penumbra::spaceland
