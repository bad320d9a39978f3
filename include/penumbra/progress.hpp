// What a render reports of its course in either world: progress between the passes of a
// progressive method (a path tracer), and the time each stage took.
#pragma once

#include <cstdint>
#include <string>

namespace penumbra {

struct RenderProgress {
  std::uint64_t samples = 0;  // samples per cell (2D) or pixel (3D) taken so far
  std::uint64_t target = 0;   // samples asked for (0: until the time is up)
  double elapsed_s = 0;
  double fraction = 0;  // of the work asked for (samples or time), 0..1
};

// One stage of a render (rasterise, a cascade, the G-buffer, ...) and its time.
struct StageTime {
  std::string name;
  double ms = 0;
  // The values the stage computed (intervals traced, cones merged, cells gathered, rays of the
  // fan), where a method counts them; 0: not counted. A method whose cost does not depend on
  // the scene gives the same counts for every scene of a grid size.
  std::uint64_t work = 0;
};

}  // namespace penumbra
