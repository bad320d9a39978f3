// Screen-space probes with world-space intervals (seed 000 chapters 4-5, seed 001 section 4.5):
// probes on the G-buffer's surfaces (probes.hpp, the layout), cascades of octahedral direction
// maps tracing world-space intervals with Embree (the tracer), merged top down by the 3D cascade
// core (spaceland/cascade/), and a final gather that shades every pixel. docs/METHODS.md, "SPWI".
#pragma once

#include <cstdint>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "spaceland/cascade/levels.hpp"
#include "spaceland/cascade/radiance.hpp"
#include "spaceland/gbuffer.hpp"
#include "spaceland/solve.hpp"

namespace penumbra::spaceland::spwi {

// The screen's cascades for an image and the options (derived values filled in): the levels'
// laws (probe spacing and map side x 2^step, intervals x 4^step per cascade) and each cascade's
// grid of probes (tiles).
struct Layout {
  int width = 0, height = 0;
  cascade::Levels levels;
  bool preaverage = false;  // 2x2 sub-probes per probe
  int layers = 1;           // probes per tile: 2 with the min-max merge (nearest, farthest)
  std::vector<int> nx, ny;  // tiles of each cascade
  // Temporal accumulation's jitter (shift_lattice): every cascade's tiles and probes moved by
  // this many pixels, at most half a cascade-0 spacing either way. 0 in a single render().
  int shift_x = 0, shift_y = 0;

  int count() const { return levels.count; }
  int spacing(int i) const { return levels.spacing(i); }
  int map_side(int i) const { return levels.side(i); }
  std::uint64_t probes(int i) const {
    return std::uint64_t(nx[std::size_t(i)]) * ny[std::size_t(i)] * std::uint64_t(layers);
  }
  std::uint64_t rays(int i) const { return probes(i) * levels.directions(i); }
  // Working memory: two ping-pong stores of the largest cascade (RGB floats), the probes, and
  // cascade 0's per-probe means.
  std::uint64_t bytes() const;
};

// A cascade ray's own interval, kept for the specular cone query (seed 001 2.6: U_i and T_i):
// the radiance it met there (kNoLight: no ray), and the fraction of it that went on past the
// interval's end to the cascades above.
struct Interval {
  Rgb radiance = cascade::kNoLight;
  float through = 0;
};

// The highest K any pixel of the scene reaches (its narrowest lobe; a roughness texture may make
// any lobe a mirror), at most the top cascade; 0 where no material is glossy or o.specular is not
// the cone query.
int cone_top(const Scene& scene, const cascade::Levels& levels, const SpwiOptions& o);
// What the cone query keeps of cascades 0..top: U and T below top, M and the probes above 0.
std::uint64_t cone_bytes(const Layout& layout, int top);

// The layout before the G-buffer is known (t0 = 0 is resolved later; the cascade count taken at
// its largest), for the memory check: with what the cone query keeps for the scene's materials.
std::uint64_t bytes_upper_bound(const Scene& scene, const SpwiOptions& o);

// The layout for a G-buffer: t0 and the cascade count derived where the options leave them 0.
Layout make_layout(const Scene& scene, const GBuffer& g, const SpwiOptions& o);

// Temporal accumulation's frame `frame` (SolveContext::frame) moves the probe lattice by the
// Halton point (2, 3) of its index within a cascade-0 tile, in whole pixels (probes sit on
// pixels): frame 0 not at all, and any run of frames spreads over the tile. The same shift for
// every cascade keeps each cascade's probes among the ones above as they were.
void shift_lattice(Layout& layout, std::uint64_t frame);

// The cascade-0 probe spacing for a width x height image: o.probe_spacing, or derived (0):
// kSpwiSpacing, or its half where that leaves under kSpwiProbesAcross probes across the image's
// shorter side.
int probe_spacing_for(const SpwiOptions& o, int width, int height);

// The options' ranges and combinations (directions a square of a power of two, ...), before any
// scene is read; fields are named as in SpwiOptions (`spwi.directions`).
Status check_options(const SpwiOptions& options);
// What the scene adds: SPWI carries no fog.
Status check_scene(const Scene& scene);

// Renders the camera's image; later bounces come from ctx.cache. Refuses (Error) work whose
// layout passes ctx.max_memory.
Expected<ImageRgb> render(const SolveContext& ctx, const SpwiOptions& o, const Layout& layout,
                          SolveReport& report);

}  // namespace penumbra::spaceland::spwi
