// The 2D methods as a table: one entry per method (its name, option check, memory estimate and
// solves on the CPU and GPU) that the dispatcher (render.cpp), the command line's help and the
// memory checks read. A new method is a new entry (docs/ARCHITECTURE.md walks through one).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "flatland/hrc/hrc.hpp"
#include "flatland/medium.hpp"
#include "flatland/rc/cascade.hpp"
#include "penumbra/flatland/render.hpp"

namespace penumbra::flatland {

// What a render derives from its grid and options, once: the options checked with their
// derived values filled (rc.cascades), and RC's hierarchy (sizes only; the directions are filled
// after the memory check).
struct Plan {
  int width = 0, height = 0;
  RenderOptions options;
  std::vector<rc::Cascade> cascades;  // rc
  std::uint64_t cells() const { return std::uint64_t(width) * height; }
};

// What a CPU solve works with. The dispatcher fills the medium: the scene's emission, or for a
// later bounce the scene's plus the re-emitted light of the previous one.
struct CpuSolve {
  const Scene& scene;
  const Plan& plan;
  const Medium& medium;
  hrc::Workspace& hrc;   // kept by a Renderer from one render to the next
  RenderResult& result;  // progressive methods report samples and cancellation here
};

namespace gpu {
struct MethodPasses;  // flatland/gpu/method.hpp
}

// The largest radiance (the brightest emission times the bounces) a method computes with as it
// is: far inside the float range, so that sums on the way (a path tracer's samples, the merges)
// cannot overflow. Brighter scenes are rendered at a power-of-two fraction of their light.
inline constexpr double kLargestRadiance = 0x1p64;

struct MethodEntry {
  Method method;
  const char* name;     // as to_string(), the command line and --json name it
  const char* title;    // in messages: "the path tracer"
  const char* summary;  // one line for --help
  // Long rays: the dispatcher builds the distance field and the empty blocks (when the options
  // ask for them) before the solve.
  bool skips_empty_space;
  // The method follows light through every bounce itself (pt); otherwise the dispatcher solves
  // once per bounce with the previous bounce's re-emission.
  bool bounces_itself;
  // Ranges and combinations of the method's own options for the plan's grid; fills derived
  // values. Messages name options by their field (`rc.interval`). Null: no options of its own.
  Status (*check)(Plan& plan);
  // CPU working memory beyond the medium, its skipping structures and the bounce buffers.
  std::uint64_t (*working_bytes)(const Plan& plan);
  // What helps when the memory need is too large (", or use a larger `rc.probe_spacing`").
  const char* (*memory_advice)(const RenderOptions& options);
  // The largest radiance the method's storage holds (HRC's f16 buffers); the dispatcher renders a
  // brighter scene at a power-of-two fraction of its light. Null: floats (kLargestRadiance).
  double (*largest_radiance)(const RenderOptions& options);
  // Fluence at every cell centre (3 floats per cell); stage times appended to `stages`.
  std::vector<float> (*solve)(CpuSolve& solve, std::vector<StageTime>& stages);
  // Intervals one solve traces; null when the solve counts them itself (pt's rays).
  std::uint64_t (*intervals)(const Plan& plan);
  // The GPU port; null when the method runs on the CPU only.
  const gpu::MethodPasses* gpu;
};

// Every method, in the order of the Method enum.
std::span<const MethodEntry> method_table();
const MethodEntry& entry(Method m);

// Checks the options for a grid (those every method shares, then the method's own) and derives
// the plan. Refused: what check_options refuses.
Expected<Plan> make_plan(int width, int height, const RenderOptions& options);

// Working memory of the planned render on this machine (on the GPU: the host's share).
std::uint64_t working_bytes(const Plan& plan);

}  // namespace penumbra::flatland
