// The reference path tracer (seed 004 section 5): Monte Carlo integration of the fluence at every
// cell centre through the same cell transport as the cascades, so it converges to the exact
// answer of the grid the other methods approximate.
#pragma once

#include <cstdint>
#include <vector>

#include "flatland/medium.hpp"
#include "penumbra/flatland/render.hpp"

namespace penumbra::flatland::pt {

// Cells [x0, x1) x [y0, y1) that hold emitting cells, for next event estimation, and the mean
// emitted luminance over the box (its emitting cells' luminance summed, over the box's area).
struct EmitterBox {
  int x0, y0, x1, y1;
  float radiance;
};

inline constexpr int kMaxEmitterBoxes = 32;

// Bounding boxes of the 8-connected groups of emitting cells (interacting, emission > 0). Past
// kMaxEmitterBoxes groups, groups whose centres share a tile are merged, with tiles doubling
// until few enough remain: sampling stays cheap and MIS keeps it unbiased.
std::vector<EmitterBox> find_emitters(const Medium& medium);

// Bytes the path tracer allocates beyond the medium: the sample sums, the fluence, and the
// emitter labels with next event estimation.
std::uint64_t working_bytes(int width, int height, const PtOptions& options);

// Runs passes of samples until options.pt.spp samples per cell or options.pt.seconds, or until
// options.cancel; returns the mean fluence per cell (3 floats per cell) and fills
// result.samples, result.cancelled, result.intervals (rays) and stages. The result after N
// samples does not depend on the thread count or on how the samples were split into passes.
std::vector<float> solve(const Medium& medium, const std::vector<float>& albedo,
                         const Rgb& environment, const RenderOptions& options,
                         RenderResult& result);

}  // namespace penumbra::flatland::pt
