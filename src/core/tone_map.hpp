// Display encoding shared by every world's pictures: a filmic curve and 8-bit quantisation.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/median.hpp"

namespace penumbra {

// Rec. 709 luminance of linear RGB.
inline float luminance(const float* rgb) {
  return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
}

// A light meter: the exposure (EV) that takes the median of `lit` (the luminances of the lit
// cells or pixels; reordered) to `key`. 0 when nothing is lit.
inline float meter_exposure(std::vector<float>& lit, float key) {
  return lit.empty() ? 0.0f : std::log2(key / quantile(lit, 0.5));
}

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
