// The brightest light of a 3D scene against the float range (docs/RELIABILITY.md, "Finite
// results"): refused when the radiance it can make passes a float, else rendered at 2^-k of its
// light and scaled back, which is exact (powers of two move exponents only).
#pragma once

#include "penumbra/error.hpp"
#include "penumbra/spaceland/scene.hpp"

namespace penumbra::spaceland {

// The largest radiance a method computes with: sums of a pixel's samples and weights stay far
// from overflow (as 2D's float storage).
inline constexpr double kLargestComputedRadiance = 18446744073709551616.0;  // 2^64

// k >= 0 such that the scene's radiance bound at `bounces`, times 2^-k, is at most
// kLargestComputedRadiance. Errors: the bound passes the float range (naming the brightest value
// by its JSON path), or a value is not finite (a scene built in code).
Expected<int> light_exponent(const Scene& scene, int bounces);

// The scene with its emission, sky, sun and fog emission times 2^-exponent.
Scene dimmed(const Scene& scene, int exponent);

}  // namespace penumbra::spaceland
