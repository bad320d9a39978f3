// Screen-space probes with world-space intervals (seed 000 chapters 4-5, seed 001 section 4.5):
// probes on the G-buffer's surfaces, cascades of octahedral direction maps tracing world-space
// intervals with Embree, merged top down, and a final gather that shades every pixel.
// docs/METHODS.md, "SPWI".
#pragma once

#include <cstdint>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/gbuffer.hpp"

namespace penumbra::spaceland::spwi {

// The cascade hierarchy for an image and the options (derived values filled in).
struct Plan {
  int width = 0, height = 0;
  int cascades = 0;
  int probe_spacing = 4;    // s0
  int side = 4;             // cascade 0's octahedral map is side x side directions
  float t0 = 0;             // world units
  bool preaverage = false;  // 2x2 sub-probes per probe
  int layers = 1;           // probes per tile: 2 with the min-max merge (nearest, farthest)
  std::vector<int> nx, ny;  // probe grid of each cascade

  int step = 1;  // log2 of the map side's growth per cascade: 1 (branching 4), 2 (16)

  int spacing(int i) const { return probe_spacing << (step * i); }
  int map_side(int i) const { return side << (step * i); }
  std::uint64_t probes(int i) const {
    return std::uint64_t(nx[std::size_t(i)]) * ny[std::size_t(i)] * std::uint64_t(layers);
  }
  std::uint64_t rays(int i) const {
    return probes(i) * std::uint64_t(map_side(i)) * std::uint64_t(map_side(i));
  }
  // The interval cascade i traces: [0, t0] for cascade 0, [t0 B^(i-1), t0 B^i] above, B the
  // branching (4: Alg. 6; 16: two of its steps at once).
  float interval_start(int i) const {
    return i == 0 ? 0.0f : t0 * float(1u << (2 * step * (i - 1)));
  }
  float interval_end(int i) const { return t0 * float(1u << (2 * step * i)); }
  // Working memory: two ping-pong buffers of the largest cascade (RGB floats), the probes, and
  // cascade 0's per-probe means.
  std::uint64_t bytes() const;
};

// The plan before the G-buffer is known (t0 = 0 is resolved later; the cascade count taken at
// its largest), for the memory check.
std::uint64_t bytes_upper_bound(int width, int height, const SpwiOptions& o);

struct Stats {
  std::uint64_t rays = 0;
  std::uint64_t memory_bytes = 0;
  Plan plan;
  std::vector<StageTime> stages;  // one per cascade, then the gather
};

// The options' ranges and combinations (directions a square of a power of two, ...), before any
// scene is read; fields are named as in SpwiOptions (`spwi.directions`).
Status check_options(const SpwiOptions& options);
// What the scene adds (the method table's check, run by render() after check_options, which
// covers the options): SPWI carries no fog.
Status check(const Scene& scene, const RenderOptions& options);

// Renders the camera's image. Refuses (Error) work whose plan passes options.max_memory.
Expected<ImageRgb> render(const Scene& scene, const RayScene& rays, const GBuffer& g,
                          const RenderOptions& options, Stats& stats);

}  // namespace penumbra::spaceland::spwi
