// Display encoding shared by every world's pictures: a filmic curve and 8-bit quantisation.
#pragma once

#include <algorithm>
#include <cmath>

namespace penumbra {

// Krzysztof Narkowicz's fit of the ACES filmic curve, clamped to [0, 1].
inline float aces_fit(float x) {
  if (!(x > 0)) return 0;  // negatives and NaN show as black
  x = std::min(x, 1e4f);   // the curve is already 1 there; keeps infinities out of the ratio
  const float y = (x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f);
  return std::clamp(y, 0.0f, 1.0f);
}

// [0, 1] to 0..255, rounded to nearest.
inline unsigned char to_byte(float v) {
  return static_cast<unsigned char>(std::lround(v * 255.0f));
}

}  // namespace penumbra
