// Arithmetic on linear RGB values (penumbra::Rgb) for the 3D transport.
#pragma once

#include <cmath>

#include "penumbra/image.hpp"

namespace penumbra::spaceland {

constexpr Rgb operator+(Rgb a, Rgb b) {
  return {a.r + b.r, a.g + b.g, a.b + b.b};
}
constexpr Rgb operator-(Rgb a, Rgb b) {
  return {a.r - b.r, a.g - b.g, a.b - b.b};
}
constexpr Rgb operator*(Rgb a, Rgb b) {
  return {a.r * b.r, a.g * b.g, a.b * b.b};
}
constexpr Rgb operator*(Rgb a, float s) {
  return {a.r * s, a.g * s, a.b * s};
}
constexpr Rgb operator*(float s, Rgb a) {
  return a * s;
}
constexpr Rgb& operator+=(Rgb& a, Rgb b) {
  return a = a + b;
}
constexpr Rgb& operator*=(Rgb& a, Rgb b) {
  return a = a * b;
}
constexpr Rgb& operator*=(Rgb& a, float s) {
  return a = a * s;
}
constexpr float average(Rgb a) {
  return (a.r + a.g + a.b) / 3;
}
constexpr bool is_black(Rgb a) {
  return a.r == 0 && a.g == 0 && a.b == 0;
}
constexpr float channel(Rgb a, int c) {
  return c == 0 ? a.r : c == 1 ? a.g : a.b;
}

// Per channel exp(-tau): the transmittance of an optical depth.
inline Rgb exp_neg(Rgb tau) {
  return {std::exp(-tau.r), std::exp(-tau.g), std::exp(-tau.b)};
}

}  // namespace penumbra::spaceland
