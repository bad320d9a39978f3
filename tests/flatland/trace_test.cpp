// Tracing primitives: interval merge algebra, exact cell transport against closed forms, the
// jump-flooding distance field, and the agreement of distance-field jumps with plain DDA.
#include "flatland/trace.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/math.hpp"
#include "flatland/interval.hpp"
#include "flatland/medium.hpp"
#include "flatland/rc/cascade.hpp"
#include "penumbra/flatland/scene.hpp"

namespace penumbra::flatland {
namespace {

Interval random_interval(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0, 1);
  return {3 * u(rng), 3 * u(rng), 3 * u(rng), u(rng)};
}

void expect_interval_near(const Interval& a, const Interval& b, float tol) {
  EXPECT_NEAR(a.r, b.r, tol);
  EXPECT_NEAR(a.g, b.g, tol);
  EXPECT_NEAR(a.b, b.b, tol);
  EXPECT_NEAR(a.t, b.t, tol);
}

TEST(FlatlandTrace, MergeIsAssociative) {
  std::mt19937 rng(1);
  for (int i = 0; i < 1000; ++i) {
    const Interval a = random_interval(rng), b = random_interval(rng), c = random_interval(rng);
    expect_interval_near(merge_intervals(merge_intervals(a, b), c),
                         merge_intervals(a, merge_intervals(b, c)), 1e-5f);
  }
  // The empty interval is the identity on both sides.
  const Interval a = random_interval(rng);
  expect_interval_near(merge_intervals(Interval::empty(), a), a, 0);
  expect_interval_near(merge_intervals(a, Interval::empty()), a, 0);
}

// A random scene of fog, opaque blocks and emitters; `distance` and `blocks` select the ways of
// skipping empty space.
Medium random_medium(int w, int h, unsigned seed, bool distance, bool blocks = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  Scene s;
  s.width = w;
  s.height = h;
  s.emission.assign(3 * s.cells(), 0);
  s.opacity.assign(s.cells(), 0);
  s.albedo.assign(3 * s.cells(), 0);
  for (int k = 0; k < 12; ++k) {  // blocks of random material
    const int x0 = int(u(rng) * w), y0 = int(u(rng) * h), bw = 1 + int(u(rng) * 8),
              bh = 1 + int(u(rng) * 8);
    const float op = u(rng) < 0.5f ? 1.0f : 0.3f * u(rng);
    const float le = u(rng) < 0.5f ? 2 * u(rng) : 0.0f;
    for (int y = y0; y < std::min(h, y0 + bh); ++y)
      for (int x = x0; x < std::min(w, x0 + bw); ++x) {
        s.opacity[s.index(x, y)] = op;
        for (int c = 0; c < 3; ++c) s.emission[3 * s.index(x, y) + c] = le * (1 + c);
      }
  }
  Medium m = make_medium(s);
  if (distance) build_distance_field(m);
  if (blocks) build_blocks(m);
  return m;
}

TEST(FlatlandTrace, OneIntervalEqualsTwoMergedHalves) {
  const Medium m = random_medium(64, 48, 7, false);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(0, 1);
  for (int i = 0; i < 2000; ++i) {
    const float ox = 64 * u(rng), oy = 48 * u(rng), a = float(kTwoPi) * u(rng);
    const float dx = std::cos(a), dy = std::sin(a);
    const float t0 = 10 * u(rng), t2 = t0 + 60 * u(rng), t1 = t0 + (t2 - t0) * u(rng);
    const Interval whole = trace_interval(m, ox, oy, dx, dy, t0, t2);
    const Interval split = merge_intervals(trace_interval(m, ox, oy, dx, dy, t0, t1),
                                           trace_interval(m, ox, oy, dx, dy, t1, t2));
    expect_interval_near(whole, split, 2e-4f);
  }
}

TEST(FlatlandTrace, UniformMediumMatchesBeerLambert) {
  Scene s;
  s.width = s.height = 40;
  const float opacity = 0.2f, le = 1.5f;
  s.opacity.assign(s.cells(), opacity);
  s.emission.assign(3 * s.cells(), le);
  s.albedo.assign(3 * s.cells(), 0);
  const Medium m = make_medium(s);
  const double sigma = -std::log(1.0 - opacity);
  for (float len : {0.3f, 1.0f, 7.5f, 20.0f}) {
    const float a = 0.37f;
    const Interval r = trace_interval(m, 5.2f, 6.1f, std::cos(a), std::sin(a), 0, len);
    const double tr = std::exp(-sigma * len);
    EXPECT_NEAR(r.t, tr, 1e-5) << len;
    EXPECT_NEAR(r.r, le * (1 - tr), 1e-5) << len;
  }
}

TEST(FlatlandTrace, OpaqueCellStopsTheRay) {
  Scene s;
  s.width = 10;
  s.height = 3;
  s.opacity.assign(s.cells(), 0);
  s.emission.assign(3 * s.cells(), 0);
  s.albedo.assign(3 * s.cells(), 0);
  s.opacity[s.index(3, 1)] = 0.5f;  // fog cell in front of
  s.emission[3 * s.index(3, 1)] = 2;
  s.opacity[s.index(6, 1)] = 1;  // an opaque emitter, then
  s.emission[3 * s.index(6, 1)] = 4;
  s.emission[3 * s.index(8, 1)] = 100;  // something hidden behind it
  s.opacity[s.index(8, 1)] = 1;
  const Medium m = make_medium(s);
  const Interval r = trace_interval(m, 0.5f, 1.5f, 1, 0, 0, 20);
  EXPECT_FLOAT_EQ(r.t, 0);
  EXPECT_NEAR(r.r, 2 * 0.5 + 0.5 * 4, 1e-5);  // fog: Le (1 - e^-sigma) = 2 * 0.5
  // A ray starting strictly inside an opaque cell leaves it (with skip_start) ...
  const Interval inside = trace_interval(m, 6.5f, 1.5f, -1, 0, 0, 2, true);
  EXPECT_FLOAT_EQ(inside.t, 1);
  EXPECT_FLOAT_EQ(inside.r, 0);
  // ... but one starting on its boundary enters it.
  const Interval edge = trace_interval(m, 6.0f, 1.5f, 1, 0, 0, 2, true);
  EXPECT_FLOAT_EQ(edge.r, 4);
  EXPECT_FLOAT_EQ(edge.t, 0);
  // Outside the grid nothing emits or absorbs.
  const Interval outside = trace_interval(m, -5, -5, -1, 0, 0, 100);
  EXPECT_FLOAT_EQ(outside.t, 1);
}

TEST(FlatlandTrace, DistanceFieldMatchesBruteForce) {
  const Medium m = random_medium(70, 50, 3, false);
  const std::vector<float> distance = jump_flood_distance(m);
  double worst_over = 0;
  int exact = 0;
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) {
      double best = INFINITY;
      for (int sy = 0; sy < m.height; ++sy)
        for (int sx = 0; sx < m.width; ++sx)
          if (m.step[std::size_t(sy) * m.width + sx] > 0)
            best = std::min(best, std::hypot(double(sx - x), double(sy - y)));
      const double got = distance[std::size_t(y) * m.width + x];
      worst_over = std::max(worst_over, got - best);
      exact += std::abs(got - best) < 1e-4;
    }
  EXPECT_GE(double(exact) / (double(m.width) * m.height), 0.999);
  EXPECT_LT(worst_over, 0.5);  // within the margin the tracer allows for
}

TEST(FlatlandTrace, SkippingEmptySpaceGivesTheSameAnswerAsPlainDda) {
  const Medium exact = random_medium(96, 80, 11, false);
  const Medium jumps = random_medium(96, 80, 11, true);
  const Medium blocks = random_medium(96, 80, 11, false, true);
  const Medium both = random_medium(96, 80, 11, true, true);
  int empty_blocks = 0;
  for (std::uint8_t e : blocks.block_empty) empty_blocks += e;
  ASSERT_GT(empty_blocks, 20);  // the test exercises block skips
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1);
  for (int i = 0; i < 20000; ++i) {
    float ox = 96 * u(rng), oy = 80 * u(rng), a = float(kTwoPi) * u(rng);
    if (i % 4 == 0) a = float(kPi / 2) * float(i % 16 / 4);           // axis-aligned rays
    if (i % 8 == 1) ox = std::floor(ox), oy = std::floor(oy) + 0.5f;  // starts on boundaries
    float dx = i % 4 == 0 ? std::round(std::cos(a)) : std::cos(a);
    float dy = i % 4 == 0 ? std::round(std::sin(a)) : std::sin(a);
    if (i % 8 == 3) {  // diagonal rays from cell centres or corners: through cell and block corners
      ox = std::floor(ox) + (i % 16 == 3 ? 0.5f : 0.0f),
      oy = std::floor(oy) + (i % 16 == 3 ? 0.5f : 0.0f);
      dx = (i / 8 % 2 ? 1 : -1) * 0.70710678f, dy = (i / 16 % 2 ? 1 : -1) * 0.70710678f;
    }
    if (i % 8 == 5) {  // aimed at a block corner: the block and cell exits tie up to rounding
      const float cx = 8.0f * float(i / 8 % 13), cy = 8.0f * float(i / 104 % 11);
      const float len = std::hypot(cx - ox, cy - oy);
      if (len > 0) dx = (cx - ox) / len, dy = (cy - oy) / len;
    }
    const float t1 = i % 3 == 0 ? INFINITY : 150 * u(rng);
    const Interval p = trace_interval(exact, ox, oy, dx, dy, 0, t1, true);
    for (const Medium* m : {&jumps, &blocks, &both}) {
      const Interval q = trace_interval(*m, ox, oy, dx, dy, 0, t1, true);
      ASSERT_EQ(p.t, q.t) << i;
      ASSERT_EQ(p.r, q.r) << i;
      ASSERT_EQ(p.b, q.b) << i;
    }
  }
}

TEST(FlatlandTrace, BlocksMarkExactlyTheEmptyOnes) {
  const Medium m = random_medium(70, 50, 3, false, true);
  ASSERT_EQ(m.blocks_x, 9);
  ASSERT_EQ(m.blocks_y, 7);
  for (int by = 0; by < m.blocks_y; ++by)
    for (int bx = 0; bx < m.blocks_x; ++bx) {
      bool empty = true;
      for (int y = by * 8; y < std::min(m.height, by * 8 + 8); ++y)
        for (int x = bx * 8; x < std::min(m.width, bx * 8 + 8); ++x)
          empty = empty && !(m.step[std::size_t(y) * m.width + x] > 0);
      EXPECT_EQ(m.block_empty[std::size_t(by) * m.blocks_x + bx], empty ? 1 : 0) << bx << "," << by;
    }
}

// Opaque edge cells are sharpened so a rasterised disk casts the shadow of a disk of its size:
// the width it blocks, averaged over parallel rays, is its diameter.
TEST(FlatlandTrace, OpaqueEdgesKeepTheSilhouette) {
  for (float r : {4.0f, 12.0f, 30.0f}) {
    SceneDesc d;
    d.width = d.height = 128;
    d.shapes.push_back({Circle{{64.3f, 64.1f}, r}, Material{{1, 1, 1}, 1, {}}});
    const Expected<Scene> s = build_scene(d);
    ASSERT_TRUE(s.ok());
    const Medium m = make_medium(*s);
    for (float angle : {0.1f, 0.5f, 0.785f}) {
      const float dx = std::cos(angle), dy = std::sin(angle), nx = -dy, ny = dx;
      const int n = 4000;
      double width = 0;
      for (int i = 0; i < n; ++i) {
        const float b = -(r + 4) + 2 * (r + 4) * (i + 0.5f) / n;
        width += (1 - trace_interval(m, 64.3f + nx * b - dx * 60, 64.1f + ny * b - dy * 60, dx, dy,
                                     0, 120)
                          .t) *
                 2 * (r + 4) / n;
      }
      EXPECT_NEAR(width, 2 * r, 0.4) << "r " << r << " angle " << angle;
    }
  }
}

TEST(FlatlandTrace, CascadeGeometry) {
  // Ray k of cascade n covers rays b*k .. b*k+b-1 of cascade n+1.
  for (int b : {2, 4}) {
    float dx, dy;
    rc::ray_direction(0, 4, dx, dy);
    EXPECT_NEAR(std::atan2(dy, dx), kPi / 4, 1e-6);
    for (int k = 0; k < 8; ++k) {
      double mean = 0;
      for (int c = 0; c < b; ++c) {
        rc::ray_direction(b * k + c, 8 * b, dx, dy);
        mean += std::atan2(dy, dx);
      }
      rc::ray_direction(k, 8, dx, dy);
      if (k < 3) {
        EXPECT_NEAR(mean / b, std::atan2(dy, dx), 1e-5) << "k " << k;
      }
    }
  }
  // Intervals are adjacent and grow by the branching factor; the last reaches the diagonal.
  float a0, a1, b0, b1;
  rc::cascade_interval(0, 4, 4, a0, a1);
  rc::cascade_interval(1, 4, 4, b0, b1);
  EXPECT_EQ(a0, 0);
  EXPECT_EQ(a1, 4);
  EXPECT_EQ(b0, 4);
  EXPECT_EQ(b1, 16);
  const int n = rc::cascade_count(300, 200, 4, 4);
  rc::cascade_interval(n - 1, 4, 4, a0, a1);
  EXPECT_GE(a1, std::hypot(300.0f, 200.0f));
  rc::cascade_interval(n - 2, 4, 4, a0, a1);
  EXPECT_LT(a1, std::hypot(300.0f, 200.0f));
}

}  // namespace
}  // namespace penumbra::flatland
