// The reference path tracer against closed forms and against itself: it is the ground truth the
// other methods are measured by, so these tests check that it converges to the exact answer.
#include "flatland/pt/pt.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/math.hpp"
#include "flatland/medium.hpp"
#include "penumbra/flatland/render.hpp"
#include "penumbra/flatland/scene.hpp"
#include "test_support.hpp"

namespace penumbra::flatland {
namespace {

Scene build(const SceneDesc& d) {
  return testing::build_valid(d);
}

using testing::fluence_of;
using testing::pt_options;

// An opaque disk light of radiance L in the middle of an n x n grid, black environment.
struct Disk {
  int n = 96;
  float cx = 48.3f, cy = 47.8f, r = 6, L = 1.0f;
  Scene scene() const {
    SceneDesc d;
    d.width = d.height = n;
    d.shapes.push_back({Circle{{cx, cy}, r}, Material{{L, L, L}, 1, {}}});
    return build(d);
  }
  // Cells at least 4 cells from the disk, where the rasterised disk is close to the analytic one.
  template <class F>
  void for_cells(F&& f) const {
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
        if (d >= r + 4) f(x, y, 2.0 * L * std::asin(r / d));
      }
  }
  double rmse(const ImageRgb& img) const {
    double e2 = 0;
    int cells = 0;
    for_cells([&](int x, int y, double exact) {
      e2 += std::pow(img.at(x, y).g - exact, 2);
      ++cells;
    });
    return std::sqrt(e2 / cells);
  }
};

TEST(FlatlandPt, UniformEnvironmentIsExactAtAnySampleCount) {
  SceneDesc d;
  d.width = 40;
  d.height = 30;
  d.environment = {0.5f, 1.0f, 2.0f};
  const Scene s = build(d);
  for (int spp : {1, 3, 16})
    for (Sampler sampler : {Sampler::r1, Sampler::random})
      for (bool nee : {false, true}) {
        const ImageRgb f = fluence_of(s, pt_options(spp, sampler, nee));
        for (int y = 0; y < d.height; ++y)
          for (int x = 0; x < d.width; ++x) {
            const Rgb c = f.at(x, y);
            ASSERT_NEAR(c.r, 2 * kPi * 0.5, 1e-5);
            ASSERT_NEAR(c.g, 2 * kPi * 1.0, 1e-5);
            ASSERT_NEAR(c.b, 2 * kPi * 2.0, 2e-5);
          }
      }
}

// A grid filled with a uniform emitting fog of extinction sigma in an environment E: along a
// direction the ray crosses a length l of fog to the border, so
// F = integral over theta of Le (1 - e^(-sigma l)) + E e^(-sigma l), with l(theta) in closed form.
TEST(FlatlandPt, UniformMediumMatchesTheClosedForm) {
  const int w = 32, h = 24;
  const float opacity = 0.05f, le = 2.0f, env = 0.5f;
  Scene s;
  s.width = w;
  s.height = h;
  s.environment = {env, env, env};
  s.opacity.assign(s.cells(), opacity);
  s.emission.assign(3 * s.cells(), le);
  s.albedo.assign(3 * s.cells(), 0);
  const double sigma = -std::log(1.0 - opacity);
  auto exact = [&](double px, double py) {
    const int n = 200000;  // midpoint rule; the integrand is smooth between corner directions
    double sum = 0;
    for (int k = 0; k < n; ++k) {
      const double a = 2 * kPi * (k + 0.5) / n, dx = std::cos(a), dy = std::sin(a);
      const double lx = dx > 0 ? (w - px) / dx : dx < 0 ? -px / dx : INFINITY;
      const double ly = dy > 0 ? (h - py) / dy : dy < 0 ? -py / dy : INFINITY;
      const double tr = std::exp(-sigma * std::min(lx, ly));
      sum += le * (1 - tr) + env * tr;
    }
    return sum * 2 * kPi / n;
  };
  const ImageRgb f = fluence_of(s, pt_options(1024));
  for (auto [x, y] : {std::pair{0, 0}, {5, 7}, {16, 12}, {31, 23}, {20, 3}}) {
    const double want = exact(x + 0.5, y + 0.5);
    EXPECT_NEAR(f.at(x, y).r, want, 2e-3 * want) << x << "," << y;
  }
}

// Independent random directions: the error against the closed form halves when the samples
// quadruple. 8 vs 32 samples on ~7000 cells: the noise is ~30x the rasterisation bias, and the
// ratio of two RMSEs over that many independent cells is 0.5 within about 2%.
TEST(FlatlandPt, RandomSamplerErrorHalvesAtFourTimesTheSamples) {
  const Disk disk;
  const Scene s = disk.scene();
  const double e8 = disk.rmse(fluence_of(s, pt_options(8, Sampler::random)));
  const double e32 = disk.rmse(fluence_of(s, pt_options(32, Sampler::random)));
  EXPECT_NEAR(e32 / e8, 0.5, 0.06) << e8 << " " << e32;
}

// The low-discrepancy sequence converges at least that fast, and a converged run (NEE, many
// samples) reaches the closed form within the rasterisation error.
TEST(FlatlandPt, R1ConvergesAtLeastAsFastAndReachesTheClosedForm) {
  const Disk disk;
  const Scene s = disk.scene();
  const double e8 = disk.rmse(fluence_of(s, pt_options(8)));
  const double e32 = disk.rmse(fluence_of(s, pt_options(32)));
  const double e32_random = disk.rmse(fluence_of(s, pt_options(32, Sampler::random)));
  EXPECT_LT(e32 / e8, 0.5);
  EXPECT_LT(e32, e32_random);
  const ImageRgb f = fluence_of(s, pt_options(512, Sampler::r1, true));
  double mean_rel = 0;
  int cells = 0;
  disk.for_cells([&](int x, int y, double exact) {
    mean_rel += std::abs(f.at(x, y).g - exact) / exact;
    ++cells;
  });
  EXPECT_LT(mean_rel / cells, 0.01) << mean_rel / cells;
}

// Next event estimation with MIS is unbiased: per cell, the difference between NEE and plain
// estimates (independent random numbers) averages to zero within its standard error; and NEE
// has far less error against the closed form.
TEST(FlatlandPt, NeeAgreesWithPlainSamplingAndHasLessVariance) {
  const Disk disk;
  SceneDesc d;
  d.width = d.height = disk.n;
  d.shapes.push_back({Circle{{disk.cx, disk.cy}, disk.r}, Material{{1, 1, 1}, 1, {}}});
  d.shapes.push_back({Box{{70, 30}, {4, 20}, 0.3f}, Material{}});  // something to shadow
  const Scene s = build(d);
  RenderOptions plain = pt_options(16, Sampler::random),
                nee = pt_options(16, Sampler::random, true);
  nee.pt.seed = 7;  // independent of the plain run's numbers
  const ImageRgb a = fluence_of(s, plain), b = fluence_of(s, nee);
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int y = 0; y < d.height; ++y)
    for (int x = 0; x < d.width; ++x) {
      const double diff = double(b.at(x, y).g) - a.at(x, y).g;
      sum += diff;
      sum2 += diff * diff;
      ++n;
    }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_LT(std::abs(mean) / (sd / std::sqrt(n)), 4.0) << "mean difference " << mean;
  const Scene lone = disk.scene();
  // Half the samples stay uniform (the MIS mixture), which bounds the gain; measured 0.34.
  EXPECT_LT(disk.rmse(fluence_of(lone, pt_options(16, Sampler::random, true))),
            0.5 * disk.rmse(fluence_of(lone, pt_options(16, Sampler::random))));
}

// Two bounces are the fixed-point iteration the cascades run: the same as one bounce of a scene
// whose emission is Le + albedo * F1 / 2pi, with F1 the converged direct fluence.
TEST(FlatlandPt, SecondBounceIsDirectLightOfTheReemittingScene) {
  SceneDesc d;
  d.width = d.height = 40;
  d.shapes.push_back({Box{{20, 3}, {8, 2}, 0}, Material{{6, 6, 6}, 1, {}}});  // light at the top
  d.shapes.push_back({Box{{3, 20}, {4, 36}, 0}, Material{{0, 0, 0}, 1, {0.9f, 0.2f, 0.2f}}});
  d.shapes.push_back({Box{{20, 37}, {36, 4}, 0}, Material{{0, 0, 0}, 1, {0.7f, 0.7f, 0.7f}}});
  d.shapes.push_back({Box{{26, 22}, {6, 6}, 0}, Material{{0, 0, 0}, 0.4f, {0.5f, 0.8f, 0.5f}}});
  const Scene s = build(d);
  const ImageRgb f1 = fluence_of(s, pt_options(1024, Sampler::r1, true));
  Scene s2 = s;
  const Medium m = make_medium(s);
  for (std::size_t i = 0; i < s.cells(); ++i)
    if (m.step[i] > 0)
      for (int c = 0; c < 3; ++c)
        s2.emission[3 * i + c] += s.albedo[3 * i + c] * f1.data()[3 * i + c] / float(2 * kPi);
  RenderOptions two = pt_options(1024, Sampler::r1, true);
  two.pt.seed = 3;
  two.bounces = 2;
  const ImageRgb want = fluence_of(s2, pt_options(1024, Sampler::r1, true));
  const ImageRgb got = fluence_of(s, two);
  double err = 0, norm = 0, bounce = 0;
  for (std::size_t i = 0; i < want.size(); ++i) {
    err += std::abs(got.data()[i] - want.data()[i]);
    norm += want.data()[i];
    bounce += want.data()[i] - f1.data()[i];
  }
  EXPECT_GT(bounce / norm, 0.05);  // the second bounce matters in this scene
  EXPECT_LT(err / norm, 0.01) << bounce / norm;
}

// Both methods compute the same quantity (fluence at cell centres, light arriving at wall cells),
// so the cascades land within their own error of the converged path tracer, bounces included.
TEST(FlatlandPt, CascadesAgreeWithTheConvergedPathTracer) {
  SceneDesc d;
  d.width = d.height = 64;
  d.environment = {0.05f, 0.05f, 0.05f};
  d.shapes.push_back({Circle{{16, 20}, 4}, Material{{4, 3, 2}, 1, {}}});
  d.shapes.push_back({Box{{34, 30}, {3, 30}, 0.4f}, Material{{0, 0, 0}, 1, {0.8f, 0.8f, 0.8f}}});
  d.shapes.push_back({Box{{48, 44}, {16, 16}, 0}, Material{{0, 0, 0}, 0.2f, {0.5f, 0.5f, 0.9f}}});
  const Scene s = build(d);
  for (int bounces : {1, 3}) {
    RenderOptions pt = pt_options(512, Sampler::r1, true), rc;
    pt.bounces = rc.bounces = bounces;
    const ImageRgb want = fluence_of(s, pt), got = fluence_of(s, rc);
    double err = 0, norm = 0;
    for (std::size_t i = 0; i < want.size(); ++i) {
      err += std::abs(got.data()[i] - want.data()[i]);
      norm += want.data()[i];
    }
    EXPECT_LT(err / norm, 0.03) << "bounces " << bounces;
  }
}

TEST(FlatlandPt, SameBitsOnAnyThreadCountAndAfterATimeLimit) {
  const Disk disk;
  const Scene s = disk.scene();
  RenderOptions o = pt_options(5, Sampler::r1, true);
  o.bounces = 2;
  o.threads = 1;
  const ImageRgb one = fluence_of(s, o);
  o.threads = 2;
  const ImageRgb two = fluence_of(s, o);
  ASSERT_EQ(one.size(), two.size());
  EXPECT_TRUE(std::equal(one.data(), one.data() + one.size(), two.data()));
  // A time limit splits the samples into passes of its own choosing; the result of N samples is
  // the same.
  RenderOptions timed = pt_options(0);
  timed.pt.seconds = 0.3;
  Expected<RenderResult> t = render(s, timed);
  ASSERT_TRUE(t.ok());
  EXPECT_GE(t->samples, 1u);
  const ImageRgb same = fluence_of(s, pt_options(int(t->samples)));
  EXPECT_TRUE(std::equal(same.data(), same.data() + same.size(), t->fluence.data()));
}

TEST(FlatlandPt, CancelStopsAfterTheCurrentPass) {
  const Scene s = Disk{}.scene();
  std::atomic<bool> cancel{false};
  RenderOptions o = pt_options(1000000);
  int calls = 0;
  o.progress = [&](const RenderProgress& p) {
    ++calls;
    EXPECT_EQ(p.target, 1000000u);
    cancel = true;
  };
  o.cancel = &cancel;
  Expected<RenderResult> r = render(s, o);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->cancelled);
  EXPECT_EQ(r->samples, 1u);
  EXPECT_EQ(calls, 1);
  const ImageRgb first = fluence_of(s, pt_options(1));
  EXPECT_TRUE(std::equal(first.data(), first.data() + first.size(), r->fluence.data()));
}

TEST(FlatlandPt, RefusesBadOptions) {
  const Scene s = Disk{}.scene();
  RenderOptions o = pt_options(0);
  Expected<RenderResult> r = render(s, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("time"), std::string::npos) << r.error().message;
  o = pt_options(-1);
  EXPECT_FALSE(render(s, o).ok());
  o = pt_options(4);
  o.pt.seconds = -1;
  EXPECT_FALSE(render(s, o).ok());
  o.pt.seconds = NAN;
  EXPECT_FALSE(render(s, o).ok());
}

TEST(FlatlandPt, EmitterBoxesBoundEveryLight) {
  SceneDesc d;
  d.width = d.height = 64;
  d.shapes.push_back({Box{{10, 10}, {4, 2}, 0}, Material{{1, 1, 1}, 1, {}}});
  d.shapes.push_back({Box{{40, 50}, {6, 6}, 0}, Material{{0, 2, 0}, 1, {}}});
  d.shapes.push_back({Box{{40, 20}, {6, 6}, 0}, Material{}});  // not a light
  const Medium m = make_medium(build(d));
  const std::vector<pt::EmitterBox> boxes = pt::find_emitters(m);
  ASSERT_EQ(boxes.size(), 2u);
  EXPECT_EQ(boxes[0].x0, 8);
  EXPECT_EQ(boxes[0].y0, 9);
  EXPECT_EQ(boxes[0].x1, 12);
  EXPECT_EQ(boxes[0].y1, 11);
  EXPECT_NEAR(boxes[0].radiance, 1.0f, 1e-6);
  EXPECT_EQ(boxes[1].x0, 37);
  EXPECT_EQ(boxes[1].y1, 53);
  EXPECT_NEAR(boxes[1].radiance, 2.0f / 3.0f, 1e-6);
  // Many lights are merged into at most kMaxEmitterBoxes boxes that still hold every one.
  SceneDesc many;
  many.width = many.height = 256;
  for (int k = 0; k < 300; ++k)
    many.shapes.push_back({Box{{4.0f + (k * 37) % 248, 4.0f + (k * 91) % 248}, {2, 2}, 0},
                           Material{{1, 1, 1}, 1, {}}});
  const Medium mm = make_medium(build(many));
  const std::vector<pt::EmitterBox> merged = pt::find_emitters(mm);
  EXPECT_LE(merged.size(), std::size_t(pt::kMaxEmitterBoxes));
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) {
      if (!(mm.step[std::size_t(y) * 256 + x] > 0)) continue;
      const bool inside = std::any_of(merged.begin(), merged.end(), [&](const pt::EmitterBox& b) {
        return x >= b.x0 && x < b.x1 && y >= b.y0 && y < b.y1;
      });
      ASSERT_TRUE(inside) << x << "," << y;
    }
}

}  // namespace
}  // namespace penumbra::flatland
