// The 3D reference path tracer (docs/METHODS.md, "The 3D path tracer"): unbiased for the
// bounce count asked for, next event estimation on emitters and the sun combined with cosine
// sampling by multiple importance sampling, free-flight sampling in fog, Owen-scrambled Sobol
// points per pixel.
#pragma once

#include <cstdint>

#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/gbuffer.hpp"

namespace penumbra::spaceland::pt {

struct Stats {
  std::uint64_t rays = 0;     // continuation and shadow rays traced (not the G-buffer's)
  std::uint64_t samples = 0;  // per pixel
  bool cancelled = false;
};

// Bytes of working memory per pixel (the accumulator).
inline constexpr std::uint64_t kBytesPerPixel = 3 * sizeof(double);

// Renders the radiance towards the camera of every pixel, starting from the G-buffer's first hits.
ImageRgb render(const Scene& scene, const RayScene& rays, const GBuffer& g,
                const RenderOptions& options, Stats& stats);

}  // namespace penumbra::spaceland::pt
