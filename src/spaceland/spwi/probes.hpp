// SPWI's probe layout: probes on the G-buffer's visible surfaces at the centres of screen tiles
// (seed 000 Alg. 5), and which probes of the cascade above (or of cascade 0, for a pixel) a point
// reads, with what weights: screen bilinear, bilateral on depth edges (Alg. 7), projected onto the
// probes' lines in world space (Alg. 8), or the min-max merge's two probes per tile (chapter 7).
#pragma once

#include <array>
#include <vector>

#include "penumbra/spaceland/render.hpp"
#include "spaceland/cascade/radiance.hpp"
#include "spaceland/gbuffer.hpp"
#include "spaceland/spwi/spwi.hpp"

namespace penumbra::spaceland::spwi {

using cascade::Corners;

// A probe: a visible surface point under the pixel at the centre of its tile.
struct Probe {
  Vec3 p, n;        // position (depth bias applied) and the surface's normal, faced to the camera
  float depth = 0;  // linear depth
  bool valid = false;  // false where the pixel sees the sky
};

// Screen coordinate (x or y) of the centre of the pixel at the middle of tile k of a cascade
// whose tiles are `spacing` pixels wide.
double tile_centre(int k, int spacing);

// The probes of cascade i: one per tile, or with the min-max merge two (the tile's nearest and
// farthest surface pixels, [2 t] and [2 t + 1]).
std::vector<Probe> place_probes(const Scene& scene, const GBuffer& g, const Layout& layout, int i,
                                const SpwiOptions& o);
// The 2x2 sub-probes of each tile of cascade i, at the middles of its quarters (pre-averaging).
std::vector<std::array<Probe, 4>> place_sub_probes(const Scene& scene, const GBuffer& g,
                                                   const Layout& layout, int i, float depth_bias);

// The probes of cascade `up` that a probe of the cascade below at screen point (x, y) merges with
// (--merge), normalised; false when none is left (only sky above it on the screen).
bool upper_corners(const Layout& layout, int up, double x, double y, const Probe& probe,
                   const std::vector<Probe>& upper, const SpwiOptions& o, Corners& c);

// The cascade-i probes a pixel at (x, y) with this depth and normal gathers from (Alg. 11, with
// i = 0; above, the specular cone query's): depth-aware, weighted by cos^p of the normals' angle,
// normalised; false when none is left.
bool gather_corners(const Layout& layout, int i, int x, int y, float depth, Vec3 normal,
                    const std::vector<Probe>& probes, const SpwiOptions& o, Corners& c);

}  // namespace penumbra::spaceland::spwi
