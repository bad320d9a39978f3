// Screen-space radiance cascades (seed 001 section 4.2, the Path of Exile 2 variant): probes on
// the G-buffer as SPWI places them (spwi/probes.hpp), cascade i every s0 2^i pixels with Q0 2^i
// directions in the image plane, each direction a slice through the sphere about the probe's
// view vector cut into equal-angle sectors. A cascade's interval is marched along the screen
// through the depth pyramid's level of its step; each depth sample, solid for a thickness behind
// it, sets the sectors it covers in an occlusion bitmask and adds its radiance to those it covers
// first. Merged top down: the sectors a lower interval leaves open take the upper probes'
// radiance (flatland's merge per sector); what leaves the screen sees the sky, or with
// --offscreen world what an exact ray through the scene meets. docs/METHODS.md, "Screen-space
// radiance cascades".
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "spaceland/gbuffer.hpp"
#include "spaceland/solve.hpp"
#include "spaceland/spwi/probes.hpp"
#include "spaceland/spwi/spwi.hpp"

namespace penumbra::spaceland::ssrc {

// A direction's radiance is stored in at most this many bins of adjacent sectors (4 sectors each
// at 32): the bitmask resolves occlusion finer than the radiance the cascades carry, which keeps
// a cascade's store at 8 RGB values a direction. A ray's sectors below its probe's surface take
// the nearest value above it before they are binned, so a bin across the horizon holds the light
// above it.
inline constexpr int kMaxBins = 8;
// Screen directions of a cascade-0 probe at most (the gather's weights are on the stack).
inline constexpr int kMaxDirections = 256;

// How far above a probe's tangent plane, over the distance, a sample counts as on it.
inline constexpr float kOnPlane = 0.02f;
// A camera ray counts as running along a texel's plane where (g.n)^2 <= kParallel |g|^2 |n|^2.
inline constexpr float kParallel = 1e-12f;

struct Layout {
  spwi::Layout tiles;   // the probe tiles of each cascade (levels.spacing*, nx, ny)
  int q0 = 16;          // screen directions of cascade 0
  int r0 = 16;          // cascade 0's interval, pixels
  int steps = 16;       // samples an interval at least (the top one: to the screen's edge)
  int sectors = 32;     // per direction: occlusion bits
  int bins = 8;         // per direction: stored radiance, sectors / bins sectors each
  int rays = 4;         // directions marched together
  bool glossy = false;  // a glossy material in the scene: its pixels keep more (bytes())
  // Every cascade's screen directions turned by this angle, radians (temporal accumulation's
  // jitter): the same for all, so that each direction's two children above stay its halves.
  double rotation = 0;

  int count() const { return tiles.count(); }
  int directions(int i) const { return q0 << i; }
  // Cascade i's interval in pixels along the screen: [0, r0], then [r0 2^(i-1), r0 2^i]; the
  // top one runs to the screen's edge.
  double start(int i) const { return i == 0 ? 0.0 : double(r0) * double(1u << (i - 1)); }
  double end(int i) const { return double(r0) * double(1u << i); }
  bool top(int i) const { return i == count() - 1; }
  // The angle of cascade i's screen direction d: 2 pi (d + 1/2) / directions, turned by rotation.
  double phi(int i, int d) const {
    return 2 * std::numbers::pi * (d + 0.5) / directions(i) + rotation;
  }
  // Cascade i's samples along a direction (fewer where it leaves the screen): its interval over
  // its level's step; the top cascade's, the image's diagonal over the step and 2.
  int samples(int i) const {
    const double step = double(1 << level(i));
    if (top(i))
      return int(std::ceil(std::sqrt(double(tiles.width) * tiles.width +
                                     double(tiles.height) * tiles.height) /
                           step)) +
             2;
    return int(std::floor((end(i) - start(i)) / step + 1e-9));
  }
  // The depth pyramid's level its samples read, 2^level pixels apart: the finest whose step
  // leaves at least `steps` samples in the interval.
  int level(int i) const {
    int l = 0;
    while ((end(i) - start(i)) / double(2 << l) >= double(steps)) ++l;
    return l;
  }
  std::uint64_t probes(int i) const { return tiles.probes(i); }
  // Radiance values (RGB) of cascade i: per probe, direction and bin.
  std::uint64_t values(int i) const {
    return probes(i) * std::uint64_t(directions(i)) * std::uint64_t(bins);
  }
  // Working memory: two cascades' stores, the probes, the pyramids and the per-pixel buffers.
  std::uint64_t bytes() const;
};

// The layout for a width x height image, derived values filled in (`glossy` is the caller's).
Layout make_layout(int width, int height, const SsrcOptions& o);

// The options' ranges and combinations, fields named as in SsrcOptions (`ssrc.sectors`).
Status check_options(const SsrcOptions& o);
// What the scene adds: the screen carries no fog. (Glossy materials read merged cascade 0 with
// their lobe, on the CPU.)
Status check_scene(const Scene& scene);

// What render() prepares on the CPU before the cascades, as views of its own buffers: handed to
// a port that runs the cascades, the gather and the shading elsewhere (ssrc/gpu.hpp).
struct Prepared {
  const Layout& layout;
  Vec3 eye, forward, right, up;  // the camera's frame
  float tan_half = 1;            // tan of half the vertical field of view
  // Per level of the depth pyramid: its size, the march's record of each texel (kTexelFloats
  // floats: the plane's normal, its square, the plane's offset, the mean's depth, the depth
  // range and the solid's end) and how many hits it covers (the radiance is filled per bounce).
  struct Level {
    int width = 0, height = 0;
    std::span<const std::byte> texels;
    std::span<const float> count;
  };
  std::vector<Level> levels;
  const std::vector<Rgb>& radiance;  // per pixel: what the first bounce marches (the emission)
  const std::vector<Rgb>& direct;    // per pixel: emission and the sun's light
  const std::vector<Rgb>& albedo;
  const std::vector<std::vector<spwi::Probe>>& probes;  // per cascade
  const SpwiOptions& probe_options;                     // the merge's and gather's weights
  // Per sector: cos and sin at its centre angle and its share of its bin; prefix sums of cos sin
  // and sin^2.
  std::span<const float> cos_sector, sin_sector, bin_weight, cos_sum, sin_sum;
};
// Floats in a texel's record (ssrc.cpp's Texel; the GPU's kernels read the same layout).
inline constexpr int kTexelFloats = 9;
using Port = Expected<ImageRgb> (*)(const SolveContext& ctx, const SsrcOptions& o,
                                    const Prepared& prepared, SolveReport& report);

// Renders the camera's image at ctx.bounces: each later bounce marches the previous bounce's
// image as the samples' radiance. Refuses (Error) work whose layout passes ctx.max_memory. With
// a port, the cascades and what follows are the port's (the GPU's).
Expected<ImageRgb> render(const SolveContext& ctx, const SsrcOptions& o, const Layout& layout,
                          SolveReport& report, Port port = nullptr);

}  // namespace penumbra::spaceland::ssrc
