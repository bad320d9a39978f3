// The direct radiance field renderer (seed 001 section 4.4; docs/METHODS.md, "The direct radiance
// field"): the path-traced light of whatever lies behind a window (a small scene, fog) stored in
// the surface radiance cascades of that one rectangle, then seen from any camera in front of it
// without tracing a ray: each pixel whose ray crosses the window sums the cascades' intervals,
// L0 + T0 (L1 + T1 (L2 + ...)), each read bilinearly in space and in direction.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/progress.hpp"
#include "penumbra/spaceland/scene.hpp"

namespace penumbra::spaceland {

// The rectangle corner + s u + t v, s and t in [0, 1]. The field holds the light arriving at it
// from the side cross(u, v) points to (behind the window); a camera sees the field where its ray
// crosses the window towards that side.
struct Window {
  Vec3 corner{}, u{}, v{};
};

struct FieldOptions {
  Window window;
  int texels = 64;      // cascade 0's probes along the window's longer edge (a probe a texel)
  int directions = 16;  // Q0: cascade 0's directions over the hemisphere behind the window: the
                        // square of a power of two, 4..4096; 4x more each cascade up
  float interval = 0;   // t0, world units (0: two texels)
  int cascades = 0;     // 0: until an interval spans the scene
  int spp = 32;         // path-traced samples per interval of each probe and direction
  // Each interval above cascade 0 also looks back to the start of the interval below for a
  // surface, and holds it (opaque) where one is: a surface that the pixel's ray meets but that
  // lies before the interval's start from the upper probes around it (parallax) is not lost.
  // Off: plain intervals, dark gaps at grazing surfaces (docs/METHODS.md).
  bool lead_in = true;
  int bounces = 1;  // as RenderOptions::bounces: 1 direct light only, N: N-1 more bounces
  std::uint64_t seed = 0;
  int threads = 0;                                    // 0: all hardware threads
  std::uint64_t max_memory = std::uint64_t(8) << 30;  // refuse a bake needing more
};

// Checks the options: ranges, a window that is a finite rectangle of non-zero area.
Status check_field_options(const FieldOptions& options);

// The working memory of a bake of the scene (its ray tracer and every cascade's store: the field
// keeps them all), known before anything is allocated.
std::uint64_t estimate_field_memory(const Scene& scene, const FieldOptions& options);

// A view of the window: the radiance of each pixel whose ray crosses it towards the field (black
// elsewhere), which pixels those are, and what it cost.
struct FieldView {
  ImageRgb radiance;
  std::vector<std::uint8_t> covered;  // 1 where the pixel sees the window, row by row
  double time_ms = 0;
  std::uint64_t rays = 0;  // a reference view's path-traced rays (a field view traces none)
  // A reference view's: 1 where the pixel's ray, from the window, first meets an emitter.
  std::vector<std::uint8_t> sees_emitter;
};

class RadianceField {
 public:
  // Path-traces every cascade's intervals from every probe and direction (options.spp samples
  // each, jittered over the direction's cell). Refused up front: options out of range, a scene
  // check_scene refuses, light past the float range, a bake over options.max_memory.
  static Expected<RadianceField> bake(const Scene& scene, const FieldOptions& options);

  RadianceField(RadianceField&&) noexcept;
  RadianceField& operator=(RadianceField&&) noexcept;
  ~RadianceField();

  // The field seen through the camera (its width and height): no ray is traced. Refused: a
  // camera the format would refuse (its size 1..kMaxImageSide, finite, fov_y in (0, 180)).
  Expected<FieldView> view(const Camera& camera, int threads = 0) const;
  // The light the field holds at window point (s, t) (clamped to [0, 1]) from direction
  // `towards` (pointing behind the window, unit length; one pointing in front reads the
  // horizon's directions); black for values that are not finite.
  Rgb radiance(float s, float t, Vec3 towards) const;

  // What the bake derived and cost.
  const FieldOptions& options() const;  // with t0 and the cascade count derived
  int probes_u() const;                 // cascade 0's probes along u and v
  int probes_v() const;
  std::vector<std::uint64_t> store_bytes() const;  // per cascade (M_i)
  std::vector<StageTime> stages() const;
  double bake_ms() const;
  std::uint64_t memory_bytes() const;  // peak: the ray tracer and the stores
  std::uint64_t rays() const;

 private:
  struct Impl;
  explicit RadianceField(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The path tracer's image of the same pixels, truth for a field view: each covered pixel's ray
// path-traced from where it crosses the window (what lies in front of the window is no part of
// the field), `spp` samples a pixel, the same estimator as `render --method pt`.
Expected<FieldView> reference_view(const Scene& scene, const Window& window, const Camera& camera,
                                   int spp, int bounces, std::uint64_t seed = 0, int threads = 0,
                                   std::uint64_t max_memory = std::uint64_t(8) << 30);

}  // namespace penumbra::spaceland
