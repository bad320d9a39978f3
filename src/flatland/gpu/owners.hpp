// Who each of the 2D GPU solver's buffers belongs to (gpu::Cache frees the buffers of owners a
// render does not use, so what is allocated is what its memory check counted).
#pragma once

#include "gpu/cache.hpp"

namespace penumbra::flatland::gpu {

enum Owners : penumbra::gpu::Owner {
  kSceneBuffers,  // the scene arrays, step, fluence, read back
  kBounce,        // the emission of a later bounce
  kJumps,         // jump flooding's seeds (RC with the distance field)
  kRc,            // RC's cascades, direction table and visibility weights
  kHrc,           // HRC's structure, planes and tables
  kHrcBlur,       // HRC's gathered fluence before the cross blur
  kScratch,       // the standalone kernels' (a cache of their own)
};

}  // namespace penumbra::flatland::gpu
