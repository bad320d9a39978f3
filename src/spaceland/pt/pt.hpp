// The 3D reference path tracer (docs/METHODS.md, "The 3D path tracer"): unbiased for the
// bounce count asked for, next event estimation on emitters and the sun combined with cosine
// sampling by multiple importance sampling, free-flight sampling in fog, Owen-scrambled Sobol
// points per pixel.
#pragma once

#include <cstdint>

#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "spaceland/solve.hpp"

namespace penumbra::spaceland::pt {

// Working memory of a w x h render: the accumulator, 3 doubles a pixel.
inline std::uint64_t working_bytes(int width, int height) {
  return std::uint64_t(width) * std::uint64_t(height) * 3 * sizeof(double);
}

// Renders the radiance towards the camera of every pixel, starting from the G-buffer's first hits
// (ctx.bounces of them); reports the continuation and shadow rays it traced, the samples per
// pixel, and whether ctx.cancel stopped it early.
ImageRgb render(const SolveContext& ctx, const PtOptions& pt, SolveReport& report);

}  // namespace penumbra::spaceland::pt
