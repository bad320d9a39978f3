// Flatland radiance cascades on the CPU (seed 001 sections 2-4.1, seed 002, seed 000 ch. 3).
#pragma once

#include <vector>

#include "flatland/medium.hpp"
#include "flatland/rc/cascade.hpp"
#include "penumbra/flatland/render.hpp"

namespace penumbra::flatland::rc {

// Ray intervals one solve traces: per probe and direction, one (the top cascade, vanilla and
// nearest merges), or one per child ray and upper probe (the bilinear fix); four times that
// with pre-averaging. Extension counts its short traced pieces.
std::uint64_t traced_intervals(const std::vector<Cascade>& plan, const RcOptions& options);

// Runs the cascades top down over `medium` and returns the fluence at every cell centre
// (3 floats per cell). Stage times are appended to `stages`.
std::vector<float> solve(const Medium& medium, const Rgb& environment,
                         const std::vector<Cascade>& plan, const RcOptions& options,
                         std::vector<StageTime>& stages);

}  // namespace penumbra::flatland::rc
