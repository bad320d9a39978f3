// Flatland radiance cascades on the GPU, pass for pass the CPU's (flatland/rc/rc.cpp): one
// dispatch per cascade, top down, ping-pong between two cascade buffers in the direction-first
// layout, then the fluence.
#pragma once

#include <vector>

#include "flatland/rc/cascade.hpp"
#include "gpu/cache.hpp"
#include "penumbra/flatland/render.hpp"

namespace penumbra::flatland::gpu {

using namespace penumbra::gpu;  // the dimension-free Vulkan plumbing

// Records a solve into `batch`: reads the medium (`step`: extinction or minus the jump length,
// `emission`: 3 floats per cell), writes the fluence (3 floats per cell) into `fluence`. `plan`
// has its directions filled. Each cascade is a timed pass "cascade n", then "fluence". A
// cascade larger than `binding_limit` bytes is merged a slab of directions at a time, bound at
// offsets that are multiples of the device's alignment (or of `alignment` when larger) (the
// direction-first layout keeps a slab, and the upper directions it reads, contiguous).
// Interval extension is not ported (check_options refuses it on the GPU).
Status record_rc(Cache& cache, Batch& batch, int width, int height, Buffer& step, Buffer& emission,
                 const Rgb& environment, const std::vector<rc::Cascade>& plan,
                 const RcOptions& options, Buffer& fluence, std::uint64_t binding_limit,
                 std::uint64_t alignment = 0);

// Device bytes record_rc keeps (two cascade buffers, the direction table, the fluence's
// visibility weights).
std::uint64_t rc_device_bytes(int width, int height, const std::vector<rc::Cascade>& plan);
// The largest range record_rc must bind at once: one direction of a cascade with the upper
// directions it merges, or the direction table.
std::uint64_t rc_smallest_binding(const std::vector<rc::Cascade>& plan, int branching);

}  // namespace penumbra::flatland::gpu
