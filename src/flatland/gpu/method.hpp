// A method's GPU port, as its entry in the method table (flatland/method.hpp) points to it: what
// the port runs, the device memory it needs, what must fit one binding, which buffers it owns,
// and the recording of its passes. The solver (solver.cpp) reads these and branches on no method.
#pragma once

#include <cstdint>
#include <vector>

#include "flatland/method.hpp"
#include "gpu/cache.hpp"
#include "gpu/vulkan.hpp"

namespace penumbra::flatland::gpu {

using namespace penumbra::gpu;  // the dimension-free Vulkan plumbing

// A buffer that must fit one binding: its size, what it is, and what helps when it does not.
struct Binding {
  std::uint64_t bytes;
  const char* what;
  const char* advice;
};

// What a port's recording works with: the medium on the device (`step`: extinction or minus the
// jump length; `emission`: 3 floats per cell), the fluence to write (3 floats per cell).
struct GpuSolve {
  Cache& cache;
  const Plan& plan;
  Buffer& step;
  const Scene& scene;  // on the host, as uploaded (a bounce's solve reads another emission)
  const Rgb& environment;
  Buffer& fluence;
  std::uint64_t binding_limit;  // bytes bound at once at most
  std::uint64_t alignment;      // of bound offsets, when more than the device's (0: the device's)
  std::vector<std::uint32_t> hrc_fan;  // HRC's fan cells, found on the host once per render
};

struct MethodPasses {
  // The options the port does not run, refused with a message naming the field; null: all run.
  Status (*unsupported)(const RenderOptions& options);
  // Device-local bytes the port keeps, beyond the scene, step, fluence and bounce buffers.
  std::uint64_t (*device_bytes)(const Plan& plan);
  // Buffers that must fit one binding (besides the fluence).
  void (*bindings)(const Plan& plan, const DeviceInfo& device, std::vector<Binding>& out);
  const char* grid_advice;  // what helps when the device's memory is too small
  // Whether the port reads distance-field jumps from the step buffer.
  bool (*jumps)(const RenderOptions& options);
  // The owners of the buffers a render with these options uses (the others are freed).
  void (*owners)(const RenderOptions& options, std::vector<Owner>& keep);
  // Records one solve with `emission` into `batch`.
  Status (*record)(GpuSolve& solve, Batch& batch, Buffer& emission);
};

extern const MethodPasses kRcPasses;
extern const MethodPasses kHrcPasses;

inline Status supports(const MethodPasses& m, const RenderOptions& options) {
  return m.unsupported ? m.unsupported(options) : Status{};
}

}  // namespace penumbra::flatland::gpu
