// The screen-space cascades' depth pyramid (issue 38): every texel of every level holds the least
// and greatest depth of the hits under it, checked against every pixel it covers, on odd sizes
// with misses among the hits.
#include "spaceland/ssrc/depth_pyramid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace penumbra::spaceland::ssrc {
namespace {

GBuffer random_gbuffer(int w, int h, unsigned seed, double miss_rate) {
  GBuffer g;
  g.width = w, g.height = h;
  g.forward = {0, 0, -1};
  const std::size_t n = std::size_t(w) * std::size_t(h);
  g.hits.resize(n);
  g.found.resize(n);
  g.directions.assign(n, Vec3{0, 0, -1});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  for (std::size_t k = 0; k < n; ++k) {
    g.found[k] = u(rng) >= miss_rate;
    g.hits[k].t = 0.5f + 20 * u(rng);
  }
  return g;
}

TEST(DepthPyramid, EveryTexelHoldsTheRangeOfTheHitsUnderIt) {
  constexpr float inf = std::numeric_limits<float>::infinity();
  for (auto [w, h] : {std::pair{37, 23}, std::pair{1, 1}, std::pair{64, 1}, std::pair{5, 130}}) {
    for (double miss : {0.0, 0.3, 1.0}) {
      const GBuffer g = random_gbuffer(w, h, unsigned(w * 131 + h), miss);
      const DepthPyramid p = DepthPyramid::build(g);
      ASSERT_GE(p.levels(), 1);
      const DepthPyramid::Level& top = p.level(p.levels() - 1);
      EXPECT_EQ(top.width, 1);
      EXPECT_EQ(top.height, 1);
      std::uint64_t texels = 0;
      for (int l = 0; l < p.levels(); ++l) {
        const DepthPyramid::Level& at = p.level(l);
        texels += std::uint64_t(at.width) * std::uint64_t(at.height);
        EXPECT_EQ(at.width, (w + (1 << l) - 1) >> l);
        EXPECT_EQ(at.height, (h + (1 << l) - 1) >> l);
        for (int y = 0; y < at.height; ++y)
          for (int x = 0; x < at.width; ++x) {
            float lo = inf, hi = -inf;
            for (int py = y << l; py < std::min(h, (y + 1) << l); ++py)
              for (int px = x << l; px < std::min(w, (x + 1) << l); ++px) {
                const std::size_t k = std::size_t(py) * std::size_t(w) + std::size_t(px);
                if (!g.found[k]) continue;
                lo = std::min(lo, g.linear_depth(k));
                hi = std::max(hi, g.linear_depth(k));
              }
            const std::size_t k = std::size_t(y) * std::size_t(at.width) + std::size_t(x);
            ASSERT_EQ(at.lo[k], lo)
                << w << "x" << h << " level " << l << " (" << x << ", " << y << ")";
            ASSERT_EQ(at.hi[k], hi) << w << "x" << h << " level " << l;
          }
      }
      EXPECT_EQ(DepthPyramid::bytes(w, h), texels * 2 * sizeof(float));
    }
  }
}

}  // namespace
}  // namespace penumbra::spaceland::ssrc
