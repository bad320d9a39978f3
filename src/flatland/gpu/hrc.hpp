// Holographic radiance cascades on the GPU: the passes ported so far, each the CPU's
// (flatland/hrc) to float rounding.
#pragma once

#include <vector>

#include "flatland/medium.hpp"
#include "gpu/cache.hpp"
#include "gpu/vulkan.hpp"
#include "penumbra/flatland/render.hpp"

namespace penumbra::flatland::gpu {

using namespace penumbra::gpu;  // the dimension-free Vulkan plumbing

// Eq. 21 on the GPU, as hrc::cross_blur: fluence f (3 floats per cell) and the per-cell
// transmittance over half a cell (0: opaque) in, the blurred fluence out.
Expected<std::vector<float>> cross_blur(const Context& context, int width, int height,
                                        const std::vector<float>& tau_half,
                                        const std::vector<float>& fluence);

// Records an HRC solve into `batch`, as hrc::solve (f32 or f16 storage of T and R): the world
// planes, per quadrant the rotated view, T_0..T_2, merge up, merge down and the gather, then the
// cross blur. Reads the medium (`step`, `emission`: 3 floats per cell) and the cells the fan
// gathers (hrc::fan_cells of the scene: hrc::fan_budget of them when the solve runs the fan),
// writes the fluence (3 floats per cell). Timed passes, each recorded once per quadrant:
// "views", "trace T0-T2", "merge up T3-TN", "merge down R", "fan" (with the wall fan), then
// "cross blur".
Status record_hrc(Cache& cache, Batch& batch, int width, int height, Buffer& step, Buffer& emission,
                  const std::vector<std::uint32_t>& fan, const Rgb& environment,
                  const HrcOptions& options, Buffer& fluence);

// Device bytes record_hrc keeps, and the largest single buffer among them.
std::uint64_t hrc_device_bytes(int width, int height, const HrcOptions& options);
std::uint64_t hrc_largest_buffer(int width, int height, Storage storage);

}  // namespace penumbra::flatland::gpu
