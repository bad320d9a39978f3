// Temporal accumulation of a Renderer's frames (RenderOptions::temporal; docs/VIEWER.md,
// "Temporal reuse"; seed 001 section 4.5: "each cascade can be reprojected from the previous frame
// to allow temporal accumulation"). Each frame turns ssrc's screen directions by a new fraction of
// a cascade-0 direction (jitter()), or moves spwi's probe lattice by a new offset within a
// cascade-0 tile (spwi::shift_lattice), so that successive frames sample elsewhere, and is
// blended into the result of the frames before it, reprojected to the new camera through each
// pixel's first hit. What is reprojected is the resolved image, not each cascade: the cascades'
// stores are two at a time (ssrc::Layout::bytes), and keeping every cascade of the last frame would
// multiply that by their count.
#pragma once

#include <cstdint>
#include <vector>

#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/gbuffer.hpp"

namespace penumbra::spaceland::temporal {

// Where a reprojected history pixel is refused: its material is another (a light's pixel beside
// the ceiling it hangs from would bleed its emission into it), its linear depth differs from the
// point's in the previous camera by more than this fraction of it, or its normal is further than
// acos(0.9).
inline constexpr float kDepthEdge = 0.05f;
inline constexpr float kNormalEdge = 0.9f;
// Albedo below this (per channel) is not divided out: the pixel's radiance is kept as it is.
inline constexpr float kMinAlbedo = 0.01f;

// The jitter of frame f of a history, in [0, 1): the base-2 radical inverse of f (0, 1/2, 1/4,
// 3/4, 1/8, ...), so that frame 0 is the unjittered frame render() makes and any 2^k frames in a
// row cover the interval evenly.
double jitter(std::uint64_t frame);
// The radical inverse of f in `base` (jitter() is base 2's): f's digits mirrored about the point.
double radical_inverse(std::uint64_t f, unsigned base);

// What a history's frames must share: the method and every option its image depends on (not the
// camera, the image's size, the sun or the sky: those the history follows).
struct Made {
  Method method = Method::pt;
  Device device = Device::cpu;
  int bounces = 0, sun_rays = 0, cache_probe_spacing = 0, frames = 0;
  SsrcOptions ssrc;  // temporal accumulation is ssrc's and spwi's (check_options)
  SpwiOptions spwi;
  bool operator==(const Made&) const = default;
};

// What a method reports for a frame, per G-buffer pixel (SolveReport::exact): the part of its light
// that no jitter changes (the emission and the sun's direct light), which is taken afresh each
// frame instead of blended (a moved sun's shadows move at once), and the albedo its gathered light
// is multiplied by, divided out of what is blended so that textures do not smear.
struct Exact {
  std::vector<Rgb> light, albedo;
};

// The frames before this one, at their last camera.
struct History {
  Made made;                // what the frames were made with
  std::uint64_t frame = 0;  // frames accumulated since the history began
  Camera camera;            // the last frame's
  Sun sun;                  // and its light, to tell a moved light from a changed scene
  Sky sky;
  // Per pixel: the radiance less its exact part (accumulate's `direct`) over the albedo
  // (kMinAlbedo), 0 at the sky.
  std::vector<Rgb> value;
  std::vector<float> depth;             // linear depth of its first hit, -1 where it sees the sky
  std::vector<Vec3> normal;             // that hit's normal, faced to the camera
  std::vector<std::uint32_t> material;  // and its material
  std::vector<float> count;  // frames behind `value`, at most RenderOptions::temporal.frames

  std::uint64_t bytes() const;
  void clear() { *this = History{}; }
};

// Per pixel of a frame: the history's bytes.
inline constexpr std::uint64_t kBytesPerPixel =
    sizeof(Rgb) + sizeof(float) + sizeof(Vec3) + sizeof(std::uint32_t) + sizeof(float);

// Blends `image`, the method's frame of `scene` (whose G-buffer is `g`), less `exact.light` and
// over `exact.albedo`, into `h` reprojected to the scene's camera: each pixel that finds its
// surface in the history becomes its history plus (frame - history) / n, n the history's frames
// plus one, at most `frames`; others, and the sky, are the frame as it is. Then `h` holds the
// result at this camera.
void accumulate(const Scene& scene, const GBuffer& g, const Exact& exact, int frames,
                ImageRgb& image, History& h);

}  // namespace penumbra::spaceland::temporal
