// Image comparisons the tests of both worlds share.
#pragma once

#include <cmath>
#include <cstddef>

#include "penumbra/image.hpp"

namespace penumbra::testing {

// Relative RMSE of a against b over every channel of every pixel.
inline double relative_rmse(const ImageRgb& a, const ImageRgb& b) {
  double err = 0, ref = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    const double x = a.data()[k], y = b.data()[k];
    err += (x - y) * (x - y);
    ref += y * y;
  }
  return std::sqrt(err / ref);
}

}  // namespace penumbra::testing
