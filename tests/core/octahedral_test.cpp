// The equal-area octahedral map: it inverts itself, and equal cells hold equal solid angles.
#include "core/octahedral.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace penumbra {
namespace {

TEST(Octahedral, DecodeInvertsEncodeOverTheSphere) {
  double worst = 0;
  for (int i = 0; i < 64; ++i)
    for (int j = 0; j < 128; ++j) {
      const double z = 1 - 2 * (i + 0.5) / 64, r = std::sqrt(1 - z * z);
      const double phi = 2 * std::numbers::pi * (j + 0.5) / 128;
      const Vec3 d{float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)};
      const auto uv = octahedral::encode(d);
      ASSERT_LE(std::abs(uv[0]), 1.0f);
      ASSERT_LE(std::abs(uv[1]), 1.0f);
      const Vec3 back = octahedral::decode(uv[0], uv[1]);
      worst = std::max(worst, double(length(back - d)));
    }
  EXPECT_LT(worst, 1e-5);
  // The poles and the axes.
  EXPECT_NEAR(octahedral::decode(0, 0).z, 1.0f, 1e-6f);
  EXPECT_NEAR(octahedral::decode(1, 1).z, -1.0f, 1e-6f);
  EXPECT_NEAR(octahedral::decode(1, 0).x, 1.0f, 1e-6f);
}

// The map's own atan2 over the quarter it needs: libm's to within 1e-8, exact on the axes and
// the diagonal, near 0 and near pi/2.
TEST(Octahedral, ItsArctangentIsLibmsOverTheQuarter) {
  double worst = 0;
  for (int i = 0; i <= 2000; ++i)
    for (double scale : {1.0, 1e-3, 1e-7}) {
      const double phi = std::numbers::pi / 2 * i / 2000;
      const double y = std::sin(phi) * scale, x = std::cos(phi);
      worst = std::max(worst, std::abs(octahedral::detail::quarter_atan2(y, x) - std::atan2(y, x)));
      worst = std::max(worst, std::abs(octahedral::detail::quarter_atan2(x, y) - std::atan2(x, y)));
    }
  EXPECT_LT(worst, 1e-8);
  EXPECT_EQ(octahedral::detail::quarter_atan2(0, 1), 0.0);
  EXPECT_EQ(octahedral::detail::quarter_atan2(1, 0), std::numbers::pi / 2);
  EXPECT_NEAR(octahedral::detail::quarter_atan2(2, 2), std::numbers::pi / 4, 1e-15);
}

// Solid angle of each cell of an 8x8 map, by counting a fine stratified grid of directions
// (uniform in z and phi, hence uniform in solid angle): all within counting error of 4 pi / 64.
TEST(Octahedral, EqualCellsHoldEqualSolidAngles) {
  const int side = 8, nz = 1024, nphi = 2048;
  std::vector<int> count(side * side, 0);
  for (int i = 0; i < nz; ++i)
    for (int j = 0; j < nphi; ++j) {
      const double z = 1 - 2 * (i + 0.5) / nz, r = std::sqrt(1 - z * z);
      const double phi = 2 * std::numbers::pi * (j + 0.5) / nphi;
      const auto c = octahedral::cell_of(
          Vec3{float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)}, side);
      ++count[std::size_t(c[1] * side + c[0])];
    }
  const double expected = double(nz) * nphi / (side * side);
  for (int k = 0; k < side * side; ++k)
    EXPECT_NEAR(count[std::size_t(k)] / expected, 1.0, 0.01) << "cell " << k;
  // And every cell's centre direction falls in that cell.
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) {
      const auto c = octahedral::cell_of(octahedral::cell_direction(i, j, side), side);
      EXPECT_EQ(c[0], i);
      EXPECT_EQ(c[1], j);
    }
}

}  // namespace
}  // namespace penumbra
