// Surface radiance cascades (seed 001 section 2.5.3): probes on the atlas's texels, cascade i
// a probe every 2^i texels of a chart with an octahedral map of (side0 2^i)^2 directions (4x
// per cascade, laid in the chart's direction frame) and the interval [t0 4^(i-1), t0 4^i], so
// every cascade holds about the same memory (M_i = M_0). Each interval is traced with Embree from
// the probe's surface point, on the side of the surface its direction leaves from; a direction
// that meets nothing takes the mean of its children on that side at the (up to) four
// cascade-(i+1) probes of the same chart around it that it sees along the surface, bilinearly
// weighted (a wall standing on a floor that runs under it parts them). Cascade 0's probes are
// the texels: their irradiance, with the sun's, is the baked light. Bounces feed each texel's
// reflected light back into the next solve. docs/METHODS.md, "Surface radiance cascades".
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/progress.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/atlas/atlas.hpp"
#include "spaceland/embree/ray_scene.hpp"

namespace penumbra::spaceland::atlas {

struct CascadeOptions {
  int side0 = 4;     // cascade 0's map side: side0^2 directions over the sphere, half above
  float t0 = 0;      // cascade 0's interval, world units; 0: two texels
  int cascades = 0;  // 0: enough that the last nominal interval spans the scene
  int bounces = 1;   // 1: direct light only
  // Keep cascade 0's radiance per texel (Baked::radiance): the directional data an atlas file
  // holds for glossy queries, at the cost of one more cascade-0 store.
  bool keep_radiance = false;
  // Sphere lights small for a probe's cells claimed as footprints over its cells rather than hit
  // or missed by its rays, on flat charts (cascade::SphereLights, as SPWI).
  bool small_lights = true;
};

// The side of an equal-area map holding `directions` directions; 0 where it is no square of a
// power of two in [2, 64].
inline int side_of(int directions) {
  for (int side = 2; side <= 64; side *= 2)
    if (side * side == directions) return side;
  return 0;
}

// What a bake derived and cost.
struct BakeReport {
  int cascades = 0;
  float t0 = 0;
  std::vector<std::uint64_t> probes;       // per cascade: probes placed on a covered texel
  std::vector<std::uint64_t> store_bytes;  // per cascade: its radiance store (M_i)
  std::uint64_t rays = 0;
  // What it held at most: two cascades' stores at once, the probes, the texels and their light.
  std::uint64_t memory_bytes = 0;
  std::vector<StageTime> stages;
};

// The working memory a bake of `texels` atlas texels (chart rectangles and gutters included)
// takes at most: two cascades' stores, the texels and their irradiance.
std::uint64_t bake_bytes(std::uint64_t texels, int side0);

// The baked light: per texel of the atlas, the irradiance (sky, emitters, the sun and, past the
// first bounce, the light the surfaces reflect) on each side of its surface. A probe's map holds
// the whole sphere of directions, so one set of rays gives both sides: a wall lit from inside a
// room and seen from outside needs no second bake.
struct Baked {
  Atlas atlas;
  std::vector<Texel> texels;
  // Per texel, on the side its normal points to and the other: the irradiance from the sky,
  // the emitters and (past the first bounce) the light the surfaces reflect; and the sun's, kept
  // apart so that a view can trace the sun per pixel (shadows sharper than a texel).
  std::vector<Rgb> front, back, sun_front, sun_back;
  // Where the bake kept it (CascadeOptions::keep_radiance): per texel, the last solve's radiance
  // arriving from each direction of cascade 0's side0 x side0 equal-area octahedral map of the
  // sphere (cascade::direction_map, index v side0 + u) in its chart's direction frame
  // (direction_frame), sun excluded; zero on uncovered texels. Empty otherwise.
  int side0 = 0;
  std::vector<Rgb> radiance;

  // Where a chart's rim runs on into another chart over a smooth surface (link_seams): per
  // empty texel beside a planar chart's covered ones, the point of the surface that continues
  // the chart's plane there, in its own chart. Sorted by texel; empty: no lookup leaves its chart.
  struct SeamLink {
    std::uint32_t texel = 0;  // the empty texel, index y * width + x
    std::uint32_t from = 0;   // the chart beside it
    std::uint32_t chart = 0;  // where the surface continues, and its atlas coordinates there
    Uv uv;
  };
  std::vector<SeamLink> seams;
  // Per texel (mark_walls): 1 where the flat chart it lies on runs on under a surface within a
  // texel of it (a wall standing on a floor that passes under it, a box on the ground), so the
  // texels around it may lie on either side; a lookup near one keeps to the texels it sees.
  // Empty: none marked.
  std::vector<std::uint8_t> walled;

  // The irradiance at a surface point on the side `towards` points to (minus the ray's
  // direction), from the texels around it: bilinear over the covered ones of its chart and, past
  // its rim where a seam link continues it, over the other chart's light there; the nearest
  // covered texel of the chart where none of the four counts; the sun's share too where
  // `with_sun`. Where one of the four is walled, only those whose centre the point sees along
  // the surface count (one short ray each), so that light from past a wall does not bleed in.
  Rgb irradiance_at(const Scene& scene, const RayScene& rays, const Hit& hit, Vec3 towards,
                    bool with_sun = true) const;
  // A glossy surface's specular lobe (GGX width alpha about the shading normal n, towards the
  // viewer wo) averaged over cascade 0's radiance kept per texel (`radiance`, which it needs),
  // read from the same texels as irradiance_at: seed 001 2.6's widest query. Each texel's map
  // is weighed in its own chart's frame, a cell wider than a quarter of the lobe at 4 x 4 points
  // (cascade::lobe_cells), the lobe taken no narrower than a cell. Zero where the lobe lies
  // under the surface.
  Rgb lobe_at(const Scene& scene, const RayScene& rays, const Hit& hit, Vec3 wo, Vec3 n,
              float alpha) const;

 private:
  // What irradiance_at and lobe_at share: value(k, front) of the texels around the hit, as
  // irradiance_at describes.
  template <class Value>
  Rgb read_at(const Scene& scene, const RayScene& rays, const Hit& hit, Vec3 towards,
              Value&& value) const;
  // Bilinear over the covered texels of `chart` around uv that `keep(k)`; weight 0 where none
  // of the four is.
  template <class Value, class Keep>
  Rgb within(std::uint32_t chart, Uv uv, bool front, float& weight, Value&& value,
             Keep&& keep) const;
  // Texel k's light on the side its normal points to (front) or the other.
  Rgb light(std::size_t k, bool front, bool with_sun) const;
};

// Links the empty texels along every planar chart's rim (mesh charts not made from lightmap UVs,
// disks) to the surface that continues the chart there: the point a short ray along the rim
// texel's normal meets within 1.5 texels of the chart's plane extended, on another chart, facing
// within 45 degrees of the rim's normal (a crease, such as a box's edge, is no continuation).
// docs/METHODS.md, "Across seams".
void link_seams(const Scene& scene, const RayScene& rays, Baked& baked);

// Marks the walled texels (Baked::walled): those of a flat chart (planar, every texel's normal
// its plane's) from whose
// centre, lifted a twentieth of a texel off the surface on either side, a ray to one of its
// eight neighbours' centres (on the chart's plane extended, past its rim too) meets a surface.
// docs/METHODS.md, "Walls across a chart".
void mark_walls(const RayScene& rays, Baked& baked);

// Bakes the scene's light into a new atlas (`atlas_options`). Errors: the atlas's, options out of
// range, a store larger than `max_bytes`.
Expected<Baked> bake(const Scene& scene, const RayScene& rays, const Options& atlas_options,
                     const CascadeOptions& o, std::uint64_t max_bytes, BakeReport& report);

}  // namespace penumbra::spaceland::atlas
