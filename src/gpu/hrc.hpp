// Holographic radiance cascades on the GPU: the passes ported so far, each the CPU's
// (flatland/hrc) to float rounding.
#pragma once

#include <vector>

#include "gpu/vulkan.hpp"

namespace penumbra::gpu {

// Eq. 21 on the GPU, as hrc::cross_blur: fluence f (3 floats per cell) and the per-cell
// transmittance over half a cell (0: opaque) in, the blurred fluence out.
Expected<std::vector<float>> cross_blur(const Context& context, int width, int height,
                                        const std::vector<float>& tau_half,
                                        const std::vector<float>& fluence);

}  // namespace penumbra::gpu
