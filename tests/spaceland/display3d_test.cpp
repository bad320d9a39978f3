// The 3D display's automatic exposure: the median luminance of the lit pixels of a radiance or
// emission image goes to kAutoExposureKey; the other images are not exposed.
#include <gtest/gtest.h>

#include <cmath>

#include "penumbra/spaceland/io.hpp"

namespace penumbra::spaceland {
namespace {

ImageRgb uniform(int w, int h, float v) {
  ImageRgb img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.set(x, y, {v, v, v});
  return img;
}

TEST(Display3d, AutoExposureMetersTheMedianLitPixel) {
  for (float r : {0.02f, 1.0f, 40.0f})
    EXPECT_NEAR(auto_exposure(uniform(6, 4, r), Aov::radiance), std::log2(kAutoExposureKey / r),
                1e-5f)
        << r;
  ImageRgb img = uniform(3, 1, 0.5f);
  img.set(0, 0, {0, 0, 0});     // a miss into a black sky: not metered
  img.set(1, 0, {50, 50, 50});  // the light itself
  // Lit: 50 and 0.5; the median of two is the upper one.
  EXPECT_NEAR(auto_exposure(img, Aov::emission), std::log2(kAutoExposureKey / 50), 1e-5f);
  for (Aov aov : {Aov::albedo, Aov::normal, Aov::depth, Aov::position, Aov::object})
    EXPECT_EQ(auto_exposure(uniform(2, 2, 3), aov), 0.0f);
  EXPECT_EQ(auto_exposure(uniform(2, 2, 0), Aov::radiance), 0.0f);
}

}  // namespace
}  // namespace penumbra::spaceland
