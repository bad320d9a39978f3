// Constants every world shares, defined once.
#pragma once

#include <numbers>

namespace penumbra {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kTwoPi = 2 * std::numbers::pi;

}  // namespace penumbra
