// The dimension-free helpers every world uses: half floats, huge-page arrays, constants.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/half.hpp"
#include "core/huge_pages.hpp"
#include "core/math.hpp"
#include "core/tone_map.hpp"

namespace penumbra {
namespace {

// Every one of the 65536 halves converts to the float Imath gives, and back to itself, through
// the run conversions (F16C or tables, whichever this CPU uses), in runs that are not a
// multiple of 8.
TEST(CoreHalf, RunConversionsMatchImathForEveryHalf) {
  std::vector<Half> all(65536);
  for (int i = 0; i < 65536; ++i) all[i].setBits(std::uint16_t(i));
  std::vector<float> f(all.size());
  for (std::size_t at = 0; at < all.size(); at += 1001)
    to_float(all.data() + at, f.data() + at, int(std::min<std::size_t>(1001, all.size() - at)));
  std::vector<Half> back(all.size());
  to_half(f.data(), back.data(), int(f.size()));
  for (int i = 0; i < 65536; ++i) {
    const float expected = float(all[i]);
    if (std::isnan(expected)) {
      EXPECT_TRUE(std::isnan(f[i])) << i;
      EXPECT_TRUE(back[i].isNan()) << i;
      continue;
    }
    EXPECT_EQ(std::memcmp(&f[i], &expected, sizeof(float)), 0) << i;
    EXPECT_EQ(back[i].bits(), all[i].bits()) << i;
    EXPECT_EQ(load(all[i]), expected) << i;
  }
}

// Rounding to nearest even, and overflow to infinity, as Imath's conversion does.
TEST(CoreHalf, RoundsToNearestEven) {
  const float in[] = {1.0f + 1.0f / 2048, 1.0f + 3.0f / 2048, 65504.0f, 65520.0f, -0.0f, 1e-8f};
  Half out[6];
  to_half(in, out, 6);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(out[i].bits(), Half(in[i]).bits()) << in[i];
  EXPECT_EQ(float(out[0]), 1.0f);                // a tie rounds to the even 1
  EXPECT_EQ(float(out[1]), 1.0f + 2.0f / 1024);  // and this tie up
  EXPECT_TRUE(out[3].isInfinity());
}

TEST(CoreHugeArray, GrowsOnlyAndAlignsLargeArraysToHugePages) {
  HugeArray<float> a;
  float* small = a.ensure(10);
  ASSERT_NE(small, nullptr);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(small) % 64, 0u);
  EXPECT_EQ(a.ensure(5), small);  // smaller: the same memory
  const std::size_t big = (std::size_t(4) << 20) / sizeof(float);
  float* large = a.ensure(big);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(large) % (std::size_t(2) << 20), 0u);
  EXPECT_EQ(a.n, big);
  large[big - 1] = 1;  // the whole range is usable
  a.release();
  EXPECT_EQ(a.n, 0u);
  EXPECT_EQ(a.p.get(), nullptr);
}

TEST(CoreMath, PiOnce) {
  EXPECT_EQ(kTwoPi, 2 * kPi);
  EXPECT_EQ(kPi, std::acos(-1.0));
}

TEST(CoreToneMap, AcesFitIsClampedAndMonotonic) {
  EXPECT_EQ(aces_fit(-1), 0);
  EXPECT_EQ(aces_fit(NAN), 0);
  EXPECT_EQ(aces_fit(INFINITY), 1);
  float last = 0;
  for (float x = 0.001f; x < 100; x *= 1.5f) {
    EXPECT_GE(aces_fit(x), last);
    last = aces_fit(x);
  }
  EXPECT_EQ(to_byte(1), 255);
  EXPECT_EQ(to_byte(0.5f), 128);
}

}  // namespace
}  // namespace penumbra
