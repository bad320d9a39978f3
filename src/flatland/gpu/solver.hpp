// Rendering on the GPU: RC and HRC, all bounces, with the scene and everything else kept on the
// device between renders. A re-render uploads only the rows of the scene that changed, and when
// nothing changed it rebuilds neither the medium nor the distance field (the painter relies on
// this).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "flatland/method.hpp"
#include "gpu/vulkan.hpp"
#include "penumbra/flatland/render.hpp"
#include "penumbra/flatland/scene.hpp"

namespace penumbra::flatland::gpu {

using namespace penumbra::gpu;  // the dimension-free Vulkan plumbing

class Solver {
 public:
  explicit Solver(std::shared_ptr<Context> context);
  ~Solver();
  Solver(const Solver&) = delete;
  Solver& operator=(const Solver&) = delete;

  const Context& context() const { return *context_; }

  // Fluence at every cell centre (3 floats per cell) for a plan of a method with a GPU port
  // (RC's hierarchy with its directions filled).
  // Appended to `stages`: the GPU time of each pass from timestamp queries (named "gpu ...",
  // later bounces "bounce n gpu ...", a method's passes summed where it repeats them), then
  // "setup and transfers" for the host's share of the call.
  Expected<std::vector<float>> render(const Scene& scene, const Plan& plan,
                                      std::vector<StageTime>& stages);

  // Bytes the last render copied to the GPU: the whole scene the first time and after a change
  // of grid, then only the rows that changed, plus any table that changed.
  std::uint64_t uploaded_bytes() const { return uploaded_; }

  // Binds at most `bytes` of a buffer at once (0: the device's limit), at offsets that are
  // multiples of `alignment` (when more than the device's), to test on small grids the slabs
  // that large cascades are merged in.
  void limit_binding(std::uint64_t bytes, std::uint64_t alignment = 0);

  // Device-local bytes the solver holds now (after a render: what device_bytes estimated).
  std::uint64_t allocated_bytes() const;

  // Device-local memory a render needs (all of it stays allocated between renders).
  static std::uint64_t device_bytes(const Plan& plan);
  // Refuses, before anything is allocated, a render that needs more than the device's memory.
  static Status check_memory(const DeviceInfo& device, const Plan& plan);

 private:
  struct Impl;
  std::shared_ptr<Context> context_;
  std::unique_ptr<Impl> impl_;
  std::uint64_t uploaded_ = 0;
};

}  // namespace penumbra::flatland::gpu
