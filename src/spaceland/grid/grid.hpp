// The world-space probe grid (seed 001 sections 2.5.2 and 4.3): a regular 3D grid of probes per
// cascade over the voxels (the layout), the voxel march (the tracer), the probe spacing doubling
// and the directions quadrupling per cascade (each cascade about half the memory of the one
// below), intervals doubling, merged top down by the 3D cascade core (spaceland/cascade/). Like
// SPWI's cascades, those above 0 trace from their probe and mark rays that meet a surface before
// their interval unusable, and a lower ray with no usable upper ray continues itself: no light
// leaks through a wall next to an upper probe, and closed forms stay exact.
//
// Fog: the cascades march it (Beer-Lambert with a source), the camera's rays integrate what it
// scatters towards them from the probes' mean radiance, and later bounces make each fog voxel
// re-emit its scattering coefficient times that mean radiance.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/cascade/levels.hpp"
#include "spaceland/cascade/sphere_lights.hpp"
#include "spaceland/cascade/store.hpp"
#include "spaceland/grid/clipmap.hpp"
#include "spaceland/grid/voxels.hpp"
#include "spaceland/sky.hpp"
#include "spaceland/solve.hpp"
#include "spaceland/sun.hpp"

namespace penumbra::spaceland::grid {

// One cascade's probe grid over the voxels, with its levels' values.
struct CascadePlan {
  int nx = 0, ny = 0, nz = 0;  // probes along each axis
  int spacing = 1;             // voxels between probes
  int side = 1;                // the direction map is side x side
  float t_start = 0, t_end = 0;
  std::uint64_t probes() const { return std::uint64_t(nx) * std::uint64_t(ny) * std::uint64_t(nz); }
  // Radiance per probe and direction (RGB floats).
  std::uint64_t bytes() const { return cascade::RadianceStore::bytes(probes(), side); }
};

// The grid's levels: spacing s0 2^i voxels, Q0 4^i directions, intervals t0 2^i (t0 0: four
// cascade-0 probe spacings), until an interval reaches across the grid. Errors: options out of
// range.
Expected<cascade::Levels> grid_levels(const Voxels& v, const GridOptions& o);
// The cascades for a grid of voxels, cascade 0 first.
Expected<std::vector<CascadePlan>> plan_cascades(const Voxels& v, const GridOptions& o);

// A cascade ray's own interval, kept for the specular cone query (seed 001 2.6: U_i and T_i):
// the radiance it met there (kNoLight: no ray), and the part of it that went on past the
// interval's end to the cascades above (RGB: fog colours it; 0 where a surface ended it or the
// ray went on by itself, its U then holding all it saw).
struct Interval {
  Rgb radiance = cascade::kNoLight;
  Rgb through{};
};

// The merged radiance of cascade 0: per probe, the radiance arriving along each direction; with
// glossy materials and the cone query, what it needs of cascades 0..K as well.
class RadianceField {
 public:
  // What the cone query keeps of cascade i: its own intervals (below the top K), its merged
  // radiance and directions (above 0: cascade 0's are the field's).
  struct Kept {
    std::vector<Interval> intervals;
    cascade::RadianceStore merged;
    std::vector<Vec3> dirs;
  };

  // The cosine-weighted mean radiance over the hemisphere of unit normal n at surface point p
  // (irradiance / pi), from the cascade-0 probes around p that lie in front of its surface and
  // see it; false when none does. Whether a probe sees p: with `rays`, an exact shadow ray from
  // p; without, a march through the voxels from the free voxel nearest p in front of it.
  // Cascade 0's share of the spread sphere lights is met here, at p (lights_at).
  bool mean_radiance(Vec3 p, Vec3 n, Rgb& out, const RayScene* rays = nullptr) const;
  // A glossy surface's specular lobe (seed 001 2.6's cone query): the radiance averaged over
  // GGX's D V cos of width alpha about the shading normal ns towards the viewer wo, as
  // U_0 + T_0 (U_1 + ... + T_{K-1} M_K), K = cone_cascade(alpha) up to the cascades kept
  // (cone_top; none kept: K = 0, the widest query, merged cascade 0 alone). Each cascade is read
  // from its probes around p that lie in front of its surface and see it, over the lobe no
  // narrower than one of its cells (cell_alpha); the lights met at p count in U_0, each its
  // radiance times the part of the lobe inside its cap (cascade::lobe_share). Where cascade K's
  // probes have no light in the lobe, the merged cascade below stands in. False where none has.
  bool lobe_radiance(Vec3 p, Vec3 n, Vec3 ns, Vec3 wo, float alpha, Rgb& out,
                     const RayScene* rays = nullptr) const;
  // The highest K the cone query reads (0: the widest query only).
  int cone_top() const { return kept_.empty() ? 0 : int(kept_.size()) - 1; }
  // The mean radiance over the whole sphere at a point in free space or fog (what an isotropic
  // medium scatters, per unit scattering coefficient), from the cascade-0 probes around p that
  // the voxels let it see; false when none does.
  bool sphere_radiance(Vec3 p, Rgb& out) const;

  const std::vector<CascadePlan>& cascades() const { return plan_; }
  // Milliseconds each cascade took to trace and merge (extension included), cascade 0 first.
  const std::vector<double>& cascade_ms() const { return cascade_ms_; }
  // The interval rays its cascades traced (a probe direction each; a march may take several
  // pieces: the stretch before the interval, extension, the fix's segments).
  std::uint64_t rays() const { return rays_; }
  // What it holds: cascade 0's radiance, its probes' means and marks, where its rays stopped
  // (with sphere lights).
  std::uint64_t bytes() const;

 private:
  friend class CascadeSolve;
  // Cascade 0's field: each probe's validity and its mean over the sphere.
  static RadianceField make(const Voxels& v, std::vector<CascadePlan> plan, std::vector<Vec3> dirs,
                            cascade::RadianceStore radiance, std::vector<double> ms);
  // The weighted mean of what cascade i's probes around p serve (field.cpp).
  template <class Serve, class T>
  bool tent(int i, Vec3 p, int max_radius, Serve&& serve, T& out) const;
  Vec3 free_point_near(Vec3 p, Vec3 n) const;
  // Cascade i's probes around surface point p that lie in front of it and see it, each serving
  // probe_value(q, value) (false: none) plus the `lights` it sees (lights_at's, valued by the
  // caller; cascade 0 only).
  template <class Value, class T>
  bool surface_read(int i, Vec3 p, Vec3 n, const RayScene* rays,
                    std::vector<cascade::PointLight>& lights, Value&& probe_value, T& out) const;
  // The lights cascade 0 leaves to point p (SphereLights::at_point; n zero in free space).
  void lights_at(Vec3 p, Vec3 n, std::vector<cascade::PointLight>& out) const;
  // Cascade 1's probes around a point (p, normal n, `from` a free point in front of it) that it
  // sees: the part of them whose rays towards a light find the way clear (field.cpp).
  struct UpperView {
    UpperView(Vec3 at, Vec3 normal, Vec3 free) : p(at), n(normal), from(free) {}
    Vec3 p, n, from;
    bool ready = false, none = false;
    cascade::Corners around;
    cascade::Uppers up;
    float clear(const RadianceField& f, const cascade::PointLight& pl);
  };

  const Voxels* voxels_ = nullptr;
  std::vector<CascadePlan> plan_;
  std::vector<Vec3> dirs_;
  cascade::RadianceStore radiance_;  // cascade 0
  std::vector<Rgb> sphere_;          // cascade 0: each probe's mean over its directions
  std::vector<std::uint8_t> valid_;  // cascade-0 probes outside opaque voxels
  std::vector<double> cascade_ms_;
  std::uint64_t rays_ = 0;
  // The sphere lights cascade 0 leaves to the points that read it, and where each of its rays
  // stopped, its merged continuation included (probe-major; empty without lights).
  cascade::SphereLights lights_;
  std::vector<float> reach_;
  std::vector<float> reach1_;  // cascade 1's, likewise (empty with one cascade)
  cascade::Levels levels_;
  std::vector<Kept> kept_;  // cascades 0..cone_top() (empty: the widest query only)
};

// The fields of a clipmap's levels (clipmap.hpp), finest first: a point reads the finest level
// around it, blended into the next over a band by its cut faces.
struct LevelFields {
  const Clipmap* map = nullptr;
  std::vector<RadianceField> fields;
  // RadianceField's, over the levels.
  bool mean_radiance(Vec3 p, Vec3 n, Rgb& out, const RayScene* rays = nullptr) const;
  bool lobe_radiance(Vec3 p, Vec3 n, Vec3 ns, Vec3 wo, float alpha, Rgb& out,
                     const RayScene* rays = nullptr) const;
  bool sphere_radiance(Vec3 p, Rgb& out) const;
  std::uint64_t rays() const;
};

// The radiance fog at x scatters, per unit sigma_s: the field's mean over the sphere (none where
// no probe is seen) and the sun's irradiance spread over 4 pi (its shadow rays counted in `rays`).
template <class Field>
Rgb in_scattered(const Field& field, const SunLight* sun, Vec3 x, std::uint64_t& rays) {
  Rgb in{};
  field.sphere_radiance(x, in);
  if (sun && sun->on()) in += sun->at(x, rays) * float(1 / (4 * std::numbers::pi));
  return in;
}

// Traces and merges every cascade, top down; rays that leave the grid go on through v.outer (a
// clipmap's coarser levels) and then see the sky (the sun is the renderer's, one shadow ray per
// pixel), and `lights` (the sphere lights the voxels leave out: Clipmap::lights, or
// SphereLights(scene, voxel) for one grid) are spread over the cells that see them. Refuses (Error)
// plans whose memory passes `max_bytes` (two cascades' radiance at once: the largest and the one
// above it).
// With o.specular cone and `narrowest` (the scene's narrowest lobe, cascade::narrowest_lobe)
// finite, it keeps what the cone query reads of cascades 0..cone_top.
Expected<RadianceField> solve(const Voxels& v, const Background& bg, const GridOptions& o,
                              std::uint64_t max_bytes,
                              const cascade::SphereLights* lights = nullptr,
                              float narrowest = cascade::kInfinity);

// solve() a slab at a time: each step() traces and merges up to a number of z layers of probes
// ("slabs") of the cascade at hand, top down and each cascade's layers in order, so that a
// Renderer can spread a solve over frames (RenderOptions::temporal.grid_slabs). A probe reads
// only the finished cascade above it, so the field is solve()'s bit for bit however the layers
// are split.
class CascadeSolve {
 public:
  // As solve() refuses. `v` and `lights` must outlive it (a Renderer's kept clipmap holds both).
  static Expected<CascadeSolve> start(const Voxels& v, const GridOptions& o,
                                      std::uint64_t max_bytes,
                                      const cascade::SphereLights* lights = nullptr,
                                      float narrowest = cascade::kInfinity);
  CascadeSolve(CascadeSolve&&) noexcept;
  CascadeSolve& operator=(CascadeSolve&&) noexcept;
  ~CascadeSolve();
  // Up to `slabs` layers, taken off it, rays leaving the grid seeing `bg` (each call's own: the
  // scene is the same, its objects may be other ones); true once every cascade is merged.
  bool step(const Background& bg, std::uint64_t& slabs);
  std::uint64_t slabs() const;  // layers in all: the cascades' nz summed
  std::uint64_t done() const;   // and traced so far
  // The field, once step() has returned true.
  RadianceField finish();

 private:
  struct State;
  explicit CascadeSolve(std::unique_ptr<State> s);
  std::unique_ptr<State> s_;
};

// Every level's cascades (level_options), level l spreading lights[l] (Clipmap::lights); the
// fields solved first hold part of `max_bytes`, the next level's cascades have the rest.
Expected<LevelFields> solve_levels(const Clipmap& map, const Background& bg, const GridOptions& o,
                                   std::uint64_t max_bytes,
                                   const std::vector<cascade::SphereLights>& lights,
                                   float narrowest = cascade::kInfinity);

// add_bounce on every level, each from its own field (`base`, `normals`: per level). A level's
// rays read the coarser levels' voxels: all are lit before any is solved again.
std::uint64_t add_bounces(Clipmap& map, const LevelFields& fields,
                          const std::vector<std::vector<Rgb>>& base, const SunLight* sun,
                          std::vector<std::vector<Vec3>>* normals = nullptr);

// One more bounce: every surface voxel's emission becomes `base` (its own) plus its albedo times
// the mean radiance the field brings to it, about the normal its free 6-neighbours give, plus
// the sun's light reflected (when `sun` is on); a voxel with free neighbours on both sides of
// one axis (a wall one voxel thick) gets a value for each side (Voxels::thin; a voxel thin along
// two axes, a rod, keeps `base`); a fog voxel's becomes `base` plus its scattering coefficient
// times the sphere's mean radiance there (the sun's irradiance over 4 pi included).
// `normals`, when given, receives each surface voxel's normal (a thin wall's + side's; zero
// where it has none). Returns the shadow rays it traced towards the sun.
std::uint64_t add_bounce(Voxels& v, const RadianceField& field, const std::vector<Rgb>& base,
                         const SunLight* sun = nullptr, std::vector<Vec3>* normals = nullptr);

// What the cone query keeps of cascades 0..top: U and T below top, M and the directions above 0.
std::uint64_t cone_bytes(const std::vector<CascadePlan>& plan, int top);

// Working bytes of two cascades' radiance at once, the largest pair (with extension, the lower
// one's intervals twice over besides; with sphere lights to spread, where each ray stopped),
// plus what the cone query keeps of cascades 0..cone_top.
std::uint64_t cascades_bytes(const std::vector<CascadePlan>& plan, const GridOptions& o,
                             float voxel, bool lights = false, int cone_top = 0);

// How many times cascade c's traced intervals are doubled (0: traced whole).
int extension_doublings(const CascadePlan& c, const GridOptions& o, float voxel, bool top);

// How many voxels in radius a sphere light must reach to be voxelised rather than spread
// (cascade::kSpreadVoxels). With the bilinear fix or extension, 2: their rays do not say where
// they stopped as the plain merge's do, and the spread lights' visibility rests on that.
inline float spread_voxels(const GridOptions& o) {
  return o.fix || o.extend_length > 0 ? 2.0f : cascade::kSpreadVoxels;
}

// Level l's options: an interval given in world units (the finest level's) doubles per level,
// as the voxels do.
inline GridOptions level_options(const GridOptions& o, std::size_t l) {
  GridOptions out = o;
  out.interval = o.interval * float(1 << l);
  return out;
}

// The grid's options out of range or that do not go together (any scene will do).
Status check_options(const GridOptions& o);

// The voxels' memory need, before anything is allocated.
std::uint64_t estimate_bytes(const Scene& scene, const GridOptions& o, std::uint64_t max_memory,
                             bool bounces);

// The camera's image: each pixel's first hit shows its emission, plus albedo times the mean
// radiance the probes around it bring, plus the sun through one shadow ray (and the fog's
// transmittance). With N bounces the cascades are solved N times, each after add_bounce with the
// last field. Through fog, the camera ray takes the fog's transmittance and, a probe spacing at a
// time, what the fog emits and scatters towards it (its scattering coefficient times
// sphere_radiance, plus the sun's irradiance over 4 pi where it reaches). `used` receives the
// options with their derived values (voxel, interval, cascades).
Expected<ImageRgb> render(const SolveContext& ctx, const GridOptions& o, SolveReport& report,
                          GridOptions& used);

}  // namespace penumbra::spaceland::grid
