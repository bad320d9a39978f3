// The 3D reference path tracer (docs/METHODS.md, "The 3D path tracer"): unbiased for the
// bounce count asked for, next event estimation on emitters and the sun combined with cosine
// sampling by multiple importance sampling, free-flight sampling in fog, Owen-scrambled Sobol
// points per pixel.
#pragma once

#include <cstdint>
#include <vector>

#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "spaceland/lights.hpp"
#include "spaceland/media.hpp"
#include "spaceland/solve.hpp"

namespace penumbra::spaceland::pt {

// Working memory of a w x h render: the accumulator, 3 doubles a pixel.
inline std::uint64_t working_bytes(int width, int height) {
  return std::uint64_t(width) * std::uint64_t(height) * 3 * sizeof(double);
}

// Renders the radiance towards the camera of every pixel, starting from the G-buffer's first hits
// (ctx.bounces of them); reports the continuation and shadow rays it traced, the samples per
// pixel, and whether ctx.cancel stopped it early.
ImageRgb render(const SolveContext& ctx, const PtOptions& pt, SolveReport& report);

// What one path-traced sample says of a ray's stretch [0, t_end]: the light arriving at its
// origin from the stretch (a surface met within it, fog in it, and the paths scattering there)
// and the stretch's transmittance (0 where it meets a surface, Beer-Lambert through fog).
struct Segment {
  Rgb radiance{};
  Rgb transmittance{};
};

// The path tracer for rays that start anywhere (a radiance field's intervals, a window's
// reference): the same estimator as render(), from one ray at a time.
class SegmentTracer {
 public:
  SegmentTracer(const Scene& scene, const RayScene& rays, int bounces);
  // Sample `sample` of the stretch, with the Sobol sequence scrambled by `seed`; `pieces` is
  // reused; the rays it traced are added to `rays`. t_end infinite: the whole ray, sky included.
  // lead > 0: the stretch also looks back that far before its origin for a surface, which it
  // then holds (opaque) in place of what follows; fog there is not counted.
  Segment trace(Vec3 origin, Vec3 dir, float t_end, float lead, std::uint32_t seed,
                std::uint32_t sample, std::vector<MediumPiece>& pieces, std::uint64_t& rays) const;

 private:
  const Scene& scene_;
  const RayScene& rays_;
  Lights lights_;
  Media media_;
  int bounces_;
};

}  // namespace penumbra::spaceland::pt
