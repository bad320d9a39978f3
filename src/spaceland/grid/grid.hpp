// The world-space probe grid (seed 001 sections 2.5.2 and 4.3): a regular 3D grid of probes per
// cascade over the voxels, the probe spacing doubling and the directions quadrupling per cascade
// (each cascade about half the memory of the one below), intervals doubling, merged top down.
// Like SPWI's cascades, those above 0 trace from their probe and mark rays that meet a surface
// before their interval unusable, and a lower ray with no usable upper ray continues itself: no
// light leaks through a wall next to an upper probe, and closed forms stay exact.
//
// Fog: the cascades march it (Beer-Lambert with a source), the camera's rays integrate what it
// scatters towards them from the probes' mean radiance, and later bounces make each fog voxel
// re-emit its scattering coefficient times that mean radiance.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/camera.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/gbuffer.hpp"
#include "spaceland/grid/voxels.hpp"

namespace penumbra::spaceland::grid {

struct CascadePlan {
  int nx = 0, ny = 0, nz = 0;  // probes along each axis
  int spacing = 1;             // voxels between probes
  int side = 1;                // the direction map is side x side
  float t_start = 0, t_end = 0;
  std::uint64_t probes() const { return std::uint64_t(nx) * std::uint64_t(ny) * std::uint64_t(nz); }
  // Radiance per probe and direction (RGB floats).
  std::uint64_t bytes() const;
};

// The cascades for a grid of voxels. Errors: options out of range.
Expected<std::vector<CascadePlan>> plan_cascades(const Voxels& v, const GridOptions& o);

// The merged radiance of cascade 0: per probe, the radiance arriving along each direction.
class Solution {
 public:
  // The cosine-weighted mean radiance over the hemisphere of unit normal n at surface point p
  // (irradiance / pi), from the cascade-0 probes around p that lie in front of its surface and
  // see it; false when none does. Whether a probe sees p: with `rays`, an exact shadow ray from
  // p; without, a march through the voxels from the free voxel nearest p in front of it.
  bool mean_radiance(Vec3 p, Vec3 n, Rgb& out, const RayScene* rays = nullptr) const;
  // The mean radiance over the whole sphere at a point in free space or fog (what an isotropic
  // medium scatters, per unit scattering coefficient), from the cascade-0 probes around p that
  // the voxels let it see; false when none does.
  bool sphere_radiance(Vec3 p, Rgb& out) const;

  const std::vector<CascadePlan>& cascades() const { return plan_; }
  // Milliseconds each cascade took to trace and merge (extension included), cascade 0 first.
  const std::vector<double>& cascade_ms() const { return cascade_ms_; }

 private:
  friend Expected<Solution> solve(const Voxels&, const Background&, const GridOptions&,
                                  std::uint64_t);
  const Voxels* voxels_ = nullptr;
  std::vector<CascadePlan> plan_;
  std::vector<Vec3> dirs_;
  std::vector<Rgb> radiance_;        // cascade 0, probe-major: [probe * directions + d]
  std::vector<Rgb> sphere_;          // cascade 0: each probe's mean over its directions
  std::vector<std::uint8_t> valid_;  // cascade-0 probes outside opaque voxels
  std::vector<double> cascade_ms_;
};

// Traces and merges every cascade, top down; rays that leave the grid see the sky (the sun is
// the renderer's, one shadow ray per pixel). Refuses (Error) plans whose memory passes
// `max_bytes` (two cascades' radiance at once: the largest and the one above it).
Expected<Solution> solve(const Voxels& v, const Background& bg, const GridOptions& o,
                         std::uint64_t max_bytes);

// One more bounce: every surface voxel's emission becomes `base` (its own) plus its albedo times
// the mean radiance the solution brings to it, about the normal its free 6-neighbours give, plus
// the sun's light reflected (when `sun` is on); a voxel with free neighbours on both sides of
// one axis (a wall one voxel thick) gets a value for each side (Voxels::thin; a voxel thin along
// two axes, a rod, keeps `base`); a fog voxel's
// becomes `base` plus its scattering coefficient times the sphere's mean radiance there (the sun's
// irradiance over 4 pi included).
// `normals`, when given, receives each surface voxel's normal (a thin wall's + side's; zero
// where it has none).
// Returns the shadow rays it traced towards the sun.
std::uint64_t add_bounce(Voxels& v, const Solution& sol, const std::vector<Rgb>& base,
                         const SunLight* sun = nullptr, std::vector<Vec3>* normals = nullptr);

// The world-space radiance cache other methods take their later bounces from: per surface voxel,
// the light its surfaces reflect after `bounces` bounces (albedo times the mean radiance the
// grid brings them), on top of what they emit.
class RadianceCache {
 public:
  // The reflected radiance at surface point p towards the side of unit normal n: the nearest
  // surface voxel around p whose own normal faces n's way (a surface on a voxel face marks the
  // voxels on both sides, and near an edge the other surface's too; a wall one voxel thick holds
  // both sides); 0 where there is none.
  Rgb reflected(Vec3 p, Vec3 n) const;
  // The opacity marks (the voxels' extinction), the reflected light (two sides), the normals and
  // the thin walls' marks.
  std::uint64_t bytes() const {
    return reflected_.size() * (sizeof(Rgb) * 3 + sizeof(Vec3) + sizeof(std::uint8_t));
  }

 private:
  friend Expected<RadianceCache> radiance_cache(const Scene&, const RayScene&, const RenderOptions&,
                                                int);
  Voxels voxels_;
  std::vector<Rgb> reflected_;        // towards the + side of a thin wall's axis, or any side
  std::vector<Rgb> reflected_minus_;  // thin walls: towards the - side
  std::vector<Vec3> normals_;         // thin walls: the + side's
};

// Voxelises the scene and solves the grid `bounces` times (options.grid, a quarter of
// options.max_memory for the voxels); `rays` carry the sun to the voxels.
Expected<RadianceCache> radiance_cache(const Scene& scene, const RayScene& rays,
                                       const RenderOptions& options, int bounces);

// Working bytes of two cascades' radiance at once, the largest pair (with extension, the lower
// one's intervals twice over besides).
std::uint64_t cascades_bytes(const std::vector<CascadePlan>& plan, const GridOptions& o,
                             float voxel);

// How many times cascade c's traced intervals are doubled (0: traced whole).
int extension_doublings(const CascadePlan& c, const GridOptions& o, float voxel, bool top);

// The grid's options out of range or that do not go together (spaceland::check_options calls it
// for the grid and for SPWI's later bounces; any scene will do).
Status check_options(const GridOptions& o);

// The voxel size the render uses: options.grid.voxel, or the default for a quarter of
// options.max_memory.
float voxel_size(const Scene& scene, const RenderOptions& options);

struct Stats {
  std::vector<StageTime> stages;  // voxelise, cascades, gather
  std::uint64_t rays = 0;         // shadow rays towards the sun (the cascades march voxels)
  std::uint64_t memory_bytes = 0;
  std::uint64_t voxel_bytes = 0;  // the voxels' share of memory_bytes
  float voxel = 0, t0 = 0;
  int cascades = 0;
};

// The camera's image: each pixel's first hit shows its emission, plus albedo times the mean
// radiance the probes around it bring, plus the sun through one shadow ray (and the fog's
// transmittance). With N bounces the cascades are solved N times, each after add_bounce with the
// last solution. Through fog, the camera ray takes the fog's transmittance and, a probe spacing
// at a time, what the fog emits and scatters towards it (its scattering coefficient times
// sphere_radiance, plus the sun's irradiance over 4 pi where it reaches).
Expected<ImageRgb> render(const Scene& scene, const RayScene& rays, const GBuffer& g,
                          const RenderOptions& options, Stats& stats);

}  // namespace penumbra::spaceland::grid
