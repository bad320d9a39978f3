// Running a method on a scene: options in, fluence and timings out.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/scene.hpp"

namespace penumbra {

enum class Method { rc };

// How a ray of cascade n continues into cascade n+1 when merging.
enum class MergeFix {
  bilinear,  // "bilinear fix": trace to each of the 4 upper probes, merge, then weight
  none,      // "vanilla": merge with the bilinear interpolation of the 4 upper probes
  nearest,   // merge with the nearest upper probe only (blocky; for teaching)
};

// Flatland radiance cascades (seed 001 sections 2-3, seed 002). See docs/METHODS.md.
struct RcOptions {
  int probe_spacing = 1;  // s0: cascade-0 probe spacing in cells; cascade n uses s0 * 2^n
  int directions = 4;     // Q0: directions of a cascade-0 probe
  int branching = 4;      // angular branching per cascade: 4 or 2
  float interval = 4.0f;  // t0: length of the cascade-0 interval [0, t0], in cells
  int cascades = 0;       // 0: enough that the last interval reaches past the grid diagonal
  MergeFix fix = MergeFix::bilinear;
  bool preaverage = false;  // trace a 2x2 sub-probe neighbourhood and store the average
  bool extend = false;      // build long intervals by extending a short traced one (eq. 16)
  float extend_length = 8;  // length traced before extension doubles it, in cells
};

struct RenderOptions {
  Method method = Method::rc;
  RcOptions rc;
  int bounces = 1;             // 1: direct light only; N: N-1 more diffuse bounces
  int threads = 0;             // 0: all hardware threads
  bool distance_field = true;  // jump over empty space (same answer, faster); off: plain DDA
  std::uint64_t max_memory = std::uint64_t(8) << 30;  // refuse work whose memory need is larger
};

struct StageTime {
  std::string name;
  double ms = 0;
};

struct RenderResult {
  ImageRgb fluence;                // linear RGB fluence at every cell centre
  std::vector<StageTime> stages;   // in the order they ran
  double time_ms = 0;              // computation only, no file I/O
  std::uint64_t memory_bytes = 0;  // peak working memory of the method (not the scene)
  std::uint64_t intervals = 0;     // ray intervals traced (all bounces)
  RenderOptions options;           // the options used, with derived values filled in
};

// Checks options against a grid size: ranges, combinations, and hierarchies too deep to build.
Status check_options(int width, int height, const RenderOptions& options);

// Working memory the method would need, known before anything is allocated (the largest value
// when the options are invalid).
std::uint64_t estimate_memory(const Scene& scene, const RenderOptions& options);
std::uint64_t estimate_memory(int width, int height, const RenderOptions& options);

// Bytes of a rasterised Scene of this size (emission, opacity, albedo).
std::uint64_t scene_bytes(int width, int height);

// Refuses, before anything is allocated, work whose memory need exceeds options.max_memory: the
// method's working memory, plus the rasterised scene when `with_scene` (a program that has not
// built the scene yet).
Status check_memory(int width, int height, const RenderOptions& options, bool with_scene);

// Runs the method. Refuses up front (Error, nothing allocated) when options are invalid or the
// memory estimate exceeds options.max_memory.
Expected<RenderResult> render(const Scene& scene, const RenderOptions& options);

const char* to_string(Method m);
const char* to_string(MergeFix f);

}  // namespace penumbra
