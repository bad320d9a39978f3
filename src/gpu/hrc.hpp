// Holographic radiance cascades on the GPU: the passes ported so far, each the CPU's
// (flatland/hrc) to float rounding.
#pragma once

#include <vector>

#include "flatland/medium.hpp"
#include "gpu/vulkan.hpp"
#include "penumbra/render.hpp"

namespace penumbra::gpu {

// Eq. 21 on the GPU, as hrc::cross_blur: fluence f (3 floats per cell) and the per-cell
// transmittance over half a cell (0: opaque) in, the blurred fluence out.
Expected<std::vector<float>> cross_blur(const Context& context, int width, int height,
                                        const std::vector<float>& tau_half,
                                        const std::vector<float>& fluence);

// A whole HRC solve on the GPU, as hrc::solve with f32 storage: the world planes, per quadrant
// the rotated view, T_0..T_2, merge up, merge down and the gather, then the cross blur. Fluence
// at every cell centre (3 floats per cell). Appended to `stages`: the GPU time of each pass
// (timestamp queries, summed over the quadrants) and "setup and transfers" for the rest.
Expected<std::vector<float>> hrc_solve(const Context& context, const Medium& medium,
                                       const Rgb& environment, const HrcOptions& options,
                                       std::vector<StageTime>* stages = nullptr);

}  // namespace penumbra::gpu
