// The distance field on the GPU: jump flooding, pass for pass the CPU's
// (flatland/medium.hpp jump_flood_distance), with the same tie rule, so both find the same seeds.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "flatland/medium.hpp"
#include "gpu/cache.hpp"
#include "gpu/vulkan.hpp"

namespace penumbra::flatland::gpu {

using namespace penumbra::gpu;  // the dimension-free Vulkan plumbing

// Distance from each cell centre to the nearest interacting cell centre (infinity for none).
// GPU time per pass is appended to `passes` when the device has timestamps.
Expected<std::vector<float>> jump_flood_distance(
    const Context& context, const Medium& medium,
    std::vector<std::pair<std::string, double>>* passes = nullptr);

// Records build_distance_field into `batch`: the jump length of every empty cell written into
// `step` (a medium's step values without jumps), as one timed pass "distance field".
Status record_distance_field(Cache& cache, Batch& batch, int width, int height, Buffer& step);

}  // namespace penumbra::flatland::gpu
