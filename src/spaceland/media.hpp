// Homogeneous fog boxes along a ray: where the extinction changes (boxes may overlap: their
// coefficients add), transmittance (Beer-Lambert), the light the fog emits, and free-flight
// sampling with a channel picked per sample and combined over the three channels (one-sample
// MIS), so that coloured extinction stays unbiased.
#pragma once

#include <vector>

#include "penumbra/spaceland/scene.hpp"
#include "spaceland/ray.hpp"

namespace penumbra::spaceland {

// A stretch [t0, t1] of a ray with constant coefficients (per unit length).
struct MediumPiece {
  float t0 = 0, t1 = 0;
  Rgb sigma_t{}, sigma_s{}, emission{};
};

struct FreeFlight {
  bool scattered = false;
  float t = 0;   // where it scattered
  Rgb weight{};  // throughput factor: T sigma_s / p (scattered) or T / P (passed)
};

class Media {
 public:
  explicit Media(const Scene& scene) : media_(&scene.media) {}
  bool empty() const { return media_->empty(); }

  // The stretches of the ray (unit direction) in [0, tmax] where fog is, in order; `out` is
  // reused (it allocates only when it grows).
  void pieces(const Ray& ray, float tmax, std::vector<MediumPiece>& out) const;
  // exp(-optical depth) of [0, tmax] along the ray.
  Rgb transmittance(const Ray& ray, float tmax) const;

  // The fog's own light reaching the ray's origin from the stretches: integral of T(t) e(t) dt.
  static Rgb emitted(const std::vector<MediumPiece>& pieces);
  // Samples where the ray scatters first (u_channel picks the channel the distance is drawn
  // with, u the optical depth), or that it passes every stretch.
  static FreeFlight sample(const std::vector<MediumPiece>& pieces, float u_channel, float u);

 private:
  const std::vector<Medium>* media_;
};

}  // namespace penumbra::spaceland
