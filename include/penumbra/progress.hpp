// Progress of a progressive method (a path tracer), reported between its passes in either world.
#pragma once

#include <cstdint>

namespace penumbra {

struct RenderProgress {
  std::uint64_t samples = 0;  // samples per cell (2D) or pixel (3D) taken so far
  std::uint64_t target = 0;   // samples asked for (0: until the time is up)
  double elapsed_s = 0;
  double fraction = 0;  // of the work asked for (samples or time), 0..1
};

}  // namespace penumbra
