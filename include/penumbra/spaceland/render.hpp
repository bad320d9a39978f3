// Running a 3D method on a scene: options in, the camera's image and timings out.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/progress.hpp"
#include "penumbra/spaceland/scene.hpp"

namespace penumbra::spaceland {

enum class Method {
  pt,       // the reference path tracer: converges to the exact radiance the format defines
  spwi,     // screen-space probes with world-space intervals (seed 000, seed 001 section 4.5)
  grid,     // the world-space probe grid (seed 001 section 4.3): radiance cascades over voxels
  ssrc,     // screen-space radiance cascades (seed 001 section 4.2): probes and intervals on the
            // screen, filled by marching the depth buffer with an occlusion bitmask
  surface,  // surface radiance cascades (seed 001 section 2.5.3): the light baked into a texture
            // atlas of every surface, the camera's first hits looking their texels up
};

// Where a method runs (--device). Only ssrc has a 3D GPU port: gpu is refused for the others,
// naming the method (docs/GPU.md).
enum class Device { cpu, gpu };

// How a ray of an SPWI cascade continues into the probes of the cascade above (--merge).
enum class SpwiMerge {
  bilinear,    // screen-space bilinear weights of the 4 upper probes
  bilateral,   // seed 000 Alg. 7: on a depth edge, weights divided by the depth difference
  bilinear3d,  // seed 000 Alg. 8: the point projected onto the 4 probes' lines in world space
  fix,         // the 3D bilinear fix: a ray from the lower probe to each upper probe's interval
               // start, so that the merged ray is continuous (seed 002 in 2D)
  minmax,      // seed 000 chapter 7: two probes per tile, on its nearest and farthest surface,
               // interpolated in depth between them (twice the rays and memory)
};

// Where the sun's light on the visible surfaces comes from (--sun).
enum class SpwiSun {
  direct,    // a shadow ray per pixel: sharp shadows; the cascades carry the sky only
  cascades,  // seed 000: the sun's disk is in the sky the top cascade sees
};

// How the final gather averages a cascade-0 probe's directions (--gather).
enum class SpwiGather {
  pixel,  // seed 000 Alg. 11: per pixel, over the pixel's own hemisphere (4 x Q0 reads a pixel)
  probe,  // once per probe, over the probe's hemisphere; a pixel reads 4 values
};

// How a glossy surface's specular lobe reads the cascades (--specular; seed 001 section 2.6).
enum class SpecularQuery {
  cone,  // the cone query: cascades 0..K-1 unmerged, K merged, K per pixel from the roughness
         // (the first cascade whose cells are at most a quarter of the lobe's width)
  wide,  // the widest query only: cascade 0 merged, the lobe no narrower than one of its cells
  ray,   // a baseline: one exact ray along the mirror direction (sharp at any roughness)
};

// What a screen-space cascade ray sees once its march leaves the screen (--offscreen).
enum class SsrcOffscreen {
  sky,    // the sky (the seed's method: the screen is all it knows)
  world,  // the world: an exact ray from the probe along each open sector above its surface, its
          // hit's emission (and at the last of bounces > 1 the radiance cache's reflected
          // light), or the sky (SPWI's answer)
};

// What an image holds: the radiance (the methods' answer) or a G-buffer channel of the first hits
// (the same for every method). Misses: depth +inf (EXR/PFM; PNG shows them black), normal 0,
// albedo 0, position 0, emission the sky's radiance (the sun's disk included), object -1.
enum class Aov {
  radiance,  // linear RGB radiance towards the camera
  depth,     // linear depth: distance along the camera's view direction
  normal,    // shading normal facing the camera, world space
  albedo,    // the hit's albedo, texture included
  position,  // world-space hit position
  emission,  // the hit's emitted radiance
  object,    // index of the document's object (the same value in r, g and b)
};

// The reference path tracer (docs/METHODS.md, "The 3D path tracer").
struct PtOptions {
  int spp = 64;            // samples per pixel; with `seconds`, the most to take (0: no limit)
  double seconds = 0;      // > 0: add samples until this much time has passed
  std::uint64_t seed = 0;  // changes every random number; same seed, same image
};

// SPWI's derived cascade-0 probe spacing: this many pixels, or half as many where that leaves
// fewer than kSpwiProbesAcross probes across the image's shorter side (under 240 pixels).
inline constexpr int kSpwiSpacing = 4;
inline constexpr int kSpwiProbesAcross = 60;

// Screen-space probes with world-space intervals (docs/METHODS.md, "SPWI").
struct SpwiOptions {
  // With B the branching below:
  // s0: pixels between cascade-0 probes; cascade i uses s0 sqrt(B)^i. 0: derived from the image
  // (kSpwiSpacing: 4, or 2 where the image's shorter side is under 240 pixels).
  int probe_spacing = 0;
  int directions = 64;  // Q0: directions of a cascade-0 probe (a square: 4, 16, 64, ...);
                        // cascade i has Q0 B^i
  float interval = 0;   // t0: cascade 0 traces [0, t0], cascade i [t0 B^(i-1), t0 B^i], in
                        // world units (0: four probe spacings at the median depth)
  // Directions per cascade multiply by this (4: the thesis, map side x2, probe spacing x2,
  // intervals x4; 16: side x4, spacing x4, intervals x16, half the cascades).
  int branching = 4;
  int cascades = 0;  // 0: enough that the last interval reaches across the scene's bounds,
                     // at most until the probe spacing passes the image's diagonal; the
                     // top cascade's interval runs to infinity
  SpwiMerge merge = SpwiMerge::bilinear3d;
  SpwiSun sun = SpwiSun::direct;
  SpwiGather gather = SpwiGather::pixel;
  // Probes are moved towards the camera to this fraction of their depth (seed 000 Alg. 5 uses
  // 0.98 against surface acne; 1 keeps them on the surface, rays leave it by a robust offset).
  float depth_bias = 1;
  // Cascades above 0 trace from their probe (t = 0), not from their interval's start: a ray that
  // meets a surface before its interval is marked unusable, and a lower ray with no usable upper
  // ray continues itself. Stops light through walls near probes (off: the thesis' disjoint
  // intervals, which let it through).
  bool overlap = true;
  // Pre-averaging (seed 000 section 5.1): every probe's rays traced from the 2x2 sub-probes of
  // its tile and averaged (4x the rays, the same memory).
  bool preaverage = false;
  float merge_edge = 0.1f;    // bilateral merge: a depth range over the mean above this is an edge
  float gather_edge = 0.05f;  // final gather: the same test between a pixel's 4 probes
  // Final gather: each probe's weight times cos^p of the angle between its normal and the
  // pixel's (0: off, as the thesis).
  float gather_normal = 1;
  SpecularQuery specular = SpecularQuery::cone;  // glossy materials' specular lobe
  bool operator==(const SpwiOptions&) const = default;
};

// The world-space probe grid (docs/METHODS.md, "The world-space probe grid").
struct GridOptions {
  // Voxel size, world units: of the finest level (0: the scene's longest side over 128, or the
  // median distance from the camera to what it sees over 32 where that is finer; larger when
  // the voxels would pass a quarter of max_memory).
  float voxel = 0;
  // Nested grids centred on the camera (a clipmap): level l has voxels of voxel 2^l and is 136
  // voxels wide (128 and the padding) along each axis where the scene is wider; the last holds
  // the whole scene. 0: as many as that takes (at most 8); 1: one grid over the whole scene.
  int levels = 0;
  int probe_spacing = 2;  // s0: voxels between cascade-0 probes; cascade i uses s0 2^i
  int directions = 16;    // Q0: a square of a power of two; cascade i has Q0 4^i
  float interval = 0;     // t0, world units: cascade 0 traces [0, t0], cascade i
                          // [t0 2^(i-1), t0 2^i] (0: four cascade-0 probe spacings)
  int cascades = 0;       // 0: until an interval reaches across the grid; the top one runs out
                          // of the grid, to the sky
  // Interval extension (seed 001 eq. 16): 0 traces every interval whole; L > 0 traces each
  // cascade's intervals for about L voxels (the length over a power of two) and doubles them by
  // merging each with itself shifted along its direction, interpolated from the cascade's own
  // probes, until they reach their length (the top cascade, open to the sky, is traced whole).
  float extend_length = 0;
  // The bilinear fix (seed 001 section 2.4, in 3D): each ray of a probe runs from its interval's
  // start to each of the 8 upper probes' interval starts (one per child direction), instead of
  // merging its own interval with the upper probes' (32 traced pieces a ray instead of 1).
  bool fix = false;
  // Glossy materials' specular lobe: cone or wide (the exact ray is SPWI's baseline alone).
  SpecularQuery specular = SpecularQuery::cone;
};

// Screen-space radiance cascades (docs/METHODS.md, "Screen-space cascades"): cascade i has
// probes every s0 2^i pixels, Q0 2^i directions in the image plane, each a slice through the
// sphere about the view vector cut into `sectors`, and marches [r0 2^(i-1), r0 2^i] pixels.
struct SsrcOptions {
  int probe_spacing = 0;  // s0, pixels (0: as SPWI derives it, kSpwiSpacing or its half)
  int directions = 16;    // Q0: screen directions of a cascade-0 probe, a power of two
  int interval = 0;       // r0, pixels: cascade 0 marches [0, r0] (0: four probe spacings)
  int cascades = 0;       // 0: until an interval reaches across the image's diagonal
  // Samples an interval at least: each cascade reads the finest depth-pyramid level whose step
  // (2^level pixels) leaves this many in its interval.
  int steps = 16;
  // Occlusion sectors per direction, equal angles from the view vector to its opposite: 8, 16
  // or 32 (a 32, 64 or 128-bit mask for four directions marched together).
  int sectors = 32;
  int rays = 4;  // directions marched together: 1, 2 or 4 (the same image; the time differs)
  // Each depth sample is solid from its surface to `thickness` times its linear depth behind it
  // (1e30: infinitely thick, as horizon-based methods assume); with `backfaces`, to where its
  // camera ray leaves the object it entered (a second hit on the same object: one ray a pixel,
  // a back-face depth layer), `thickness` only where nothing of its object lies behind it.
  bool backfaces = false;
  float thickness = 0.05f;
  SpwiMerge merge = SpwiMerge::bilateral;  // bilinear, bilateral or bilinear3d (as SPWI's)
  float merge_edge = 0.1f;                 // the bilateral merge's edge test (as SPWI's)
  float gather_edge = 0.05f;               // the final gather's (as SPWI's)
  float gather_normal = 1;                 // the final gather's normal weight exponent
  // probe: each probe's mean for its own normal, once, and a pixel reads 4 values (exact where
  // their normals agree, as on planes; the same error as pixel on the quality scenes, a tenth of
  // the time); pixel: each pixel weighs its probes' directions for its own normal.
  SpwiGather gather = SpwiGather::probe;
  // Rays that leave the screen see the sky, or (world) go on as exact rays through the scene: a
  // cost that depends on the scene, for rooms and light from off screen.
  SsrcOffscreen offscreen = SsrcOffscreen::sky;
  // Glossy materials' specular lobe: the widest query only (merged cascade 0's bins weighed by
  // the lobe); the cone query over ssrc's own intervals is not built.
  SpecularQuery specular = SpecularQuery::wide;
  bool operator==(const SsrcOptions&) const = default;
};

// Surface radiance cascades (docs/METHODS.md, "Surface radiance cascades"): probes on the
// texels of an atlas of every surface, cascade i a probe every 2^i texels of a chart with 4^i
// times cascade 0's directions over the sphere, intervals [t0 4^(i-1), t0 4^i].
struct SurfaceOptions {
  float texel_size = 0;             // world units a texel's side (0: from `texels`)
  std::uint64_t texels = 1u << 16;  // the surfaces' texels, about, where texel_size is 0
  // Texels up to 2^refine times finer towards the lights: under 1/16 of the distance to the
  // nearest (0: one texel size). The coarsest texel grows to keep about `texels`.
  int refine = 6;
  int directions = 64;  // Q0 over the sphere: the square of a power of two, 4..4096
  float interval = 0;   // t0, world units (0: two texels)
  int cascades = 0;     // 0: until an interval spans the scene
  // A baked atlas to view from (bake() below, `penumbra bake`), made for this scene with the
  // same bounces: no cascade is traced and the options above come from the file. "": bake now.
  std::string atlas;
  // Glossy materials' specular lobe: the widest query only (cascade 0's radiance kept per texel,
  // weighed by the lobe); the cone query over the surface cascades' own intervals is not built.
  SpecularQuery specular = SpecularQuery::wide;
};

// Temporal accumulation: a Renderer's frames of a screen-space method, each jittered (ssrc's
// screen directions turned by a new fraction of a cascade-0 direction; spwi's probe lattice moved
// by a new whole-pixel offset within a cascade-0 tile), blended into the frames before it
// reprojected to the new camera (docs/VIEWER.md, "Temporal reuse"). The exact part of the light
// (emission, the sun's direct light) is taken afresh each frame. The history is kept across camera
// moves and changes of the sun and the sky (whose indirect light then lags for a few frames), and
// dropped when anything else changes. render() makes the first frame, which is the frame without
// it.
struct TemporalOptions {
  // The history's length: in each pixel whose surface the last frame saw, a new frame weighs
  // 1 / (frames behind it + 1), at least 1 / frames. 0: off.
  int frames = 0;
  // The grid's: where a Renderer's view needs its grid solved again (the sun or the sky moved, the
  // levels moved with the camera), the grid it last solved is shown while the new one is solved
  // this many slabs (z layers of one cascade's probes) a frame, then shown in its turn. 0: off
  // (solved whole in the frame that needs it, render()'s way). The frames between show the old
  // grid's light (a moved sun's direct light is each frame's own).
  int grid_slabs = 0;
};

struct RenderOptions {
  Method method = Method::pt;
  Device device = Device::cpu;
  PtOptions pt;
  SpwiOptions spwi;
  GridOptions grid;
  SsrcOptions ssrc;
  SurfaceOptions surface;
  Aov aov = Aov::radiance;
  int bounces = 1;  // 1: direct light only; N: N-1 more diffuse bounces
  // The radiance cache that methods not bouncing themselves (spwi) read their later bounces from:
  // the probe grid with grid.voxel and grid.levels, this many voxels between its cascade-0 probes
  // and the grid's defaults otherwise (docs/METHODS.md, "The radiance cache").
  int cache_probe_spacing = 4;
  // The sun on the surfaces the camera sees, for the cascades' methods (spwi with SpwiSun::direct,
  // grid): this many exact shadow rays spread over its disk, equal solid angle each, so its
  // penumbrae are soft, in steps of 1 / sun_rays (1: one towards its centre, hard shadows).
  int sun_rays = 16;
  TemporalOptions temporal;
  int threads = 0;                                    // 0: all hardware threads
  std::uint64_t max_memory = std::uint64_t(8) << 30;  // refuse work whose memory need is larger
  // Progressive methods call this from the calling thread between passes.
  std::function<void(const RenderProgress&)> progress;
  // When set to true, progressive methods stop after the current pass and return what they have.
  const std::atomic<bool>* cancel = nullptr;
};

using penumbra::StageTime;

struct RenderResult {
  ImageRgb radiance;               // the camera's image: linear RGB (or the AOV asked for)
  std::vector<StageTime> stages;   // in the order they ran
  double time_ms = 0;              // computation only (BVH build included), no file I/O
  std::uint64_t memory_bytes = 0;  // peak working memory (BVH, buffers; not the scene)
  std::uint64_t voxel_bytes = 0;   // the probe grid's voxels, part of memory_bytes (else 0)
  std::uint64_t rays = 0;          // rays traced (closest-hit and shadow)
  std::uint64_t samples = 0;       // samples per pixel in the result
  bool cancelled = false;          // stopped early through RenderOptions::cancel
  // With temporal accumulation: the frame's index in its history (0: the first, drawn without
  // one). A still camera's frame is converged from index temporal.frames - 1 on.
  std::uint64_t temporal_frame = 0;
  // With temporal.grid_slabs: the grid this frame's view asks for is under way, these slabs of it
  // done in all, and the frame shows the last grid solved; render again to go on. 0 and 0: the
  // frame shows its own grid.
  std::uint64_t grid_slabs_done = 0, grid_slabs = 0;
  RenderOptions options;  // the options used
  std::string device = "cpu";
  // What the result lacks that the options asked for (the grid's voxels far coarser than the
  // view needs, so that light near the camera is lost); the command line prints them.
  std::vector<std::string> warnings;
};

// Checks options: ranges and combinations.
Status check_options(const RenderOptions& options);

// Refuses a scene whose radiance can pass the float range at options.bounces, naming its
// brightest value (an emission, the sky, fog or the sun; a sun whose disk's radiance alone passes
// it). render() checks it too; brighter scenes that fit are rendered exactly (docs/RELIABILITY.md).
Status check_brightness(const Scene& scene, const RenderOptions& options);

// Working memory of the render (the ray tracer's BVH and the image buffers), known before
// anything is allocated.
std::uint64_t estimate_memory(const Scene& scene, const RenderOptions& options);

// Refuses, before anything is allocated, work whose memory need (the scene's arrays included)
// exceeds options.max_memory.
Status check_memory(const Scene& scene, const RenderOptions& options);

// Runs the method. Refuses up front (Error, nothing allocated) when the scene or the options are
// invalid or the memory estimate exceeds options.max_memory; never returns a value that is not
// finite (except the depth of a miss).
Expected<RenderResult> render(const Scene& scene, const RenderOptions& options);

// Renders views of one scene again and again (the viewer, `penumbra view`), keeping what does not
// depend on the camera: the ray tracer's BVH; the surface method's atlas once baked or read (for
// the same surface options and bounces; an atlas file rewritten since is read again); the grid's
// solved voxels while its levels stay where they were placed (a camera that moves less than a
// voxel, or only turns, with the same finest voxel). One method's state at a time: a radiance
// render with another method drops it (G-buffer channels and AOVs keep it). Each render compares
// the scene but its camera with the last one's (geometry, objects, materials, textures, sky, sun,
// fog) and drops what it kept when they differ, and what was made under a larger memory limit
// than the render's is made again; so its images, parameters, warnings and refusals are
// render()'s, bit for bit (its stages, rays and times are what it did). Holds its memory until
// destroyed or clear(); one thread at a time.
class Renderer {
 public:
  Renderer();
  ~Renderer();
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;
  Expected<RenderResult> render(const Scene& scene, const RenderOptions& options);
  // G-buffer channels of the camera's first hits (each an Aov but radiance), from one set of
  // camera rays through the kept BVH: what a viewer's upscaling is guided by. The same images as
  // render() with that aov; of `options`, threads and max_memory are read.
  Expected<std::vector<ImageRgb>> channels(const Scene& scene, const std::vector<Aov>& aovs,
                                           const RenderOptions& options);
  void clear();  // drops what is kept
  struct State;

 private:
  std::unique_ptr<State> state_;
};

// What bake() made and cost.
struct BakeResult {
  SurfaceOptions used;        // the texel size, t0 and cascades it derived
  int width = 0, height = 0;  // the atlas, texels
  std::size_t charts = 0;     // of them made from the file's lightmap UVs:
  std::size_t lightmap_charts = 0;
  std::uint64_t covered = 0;                       // texels on a surface
  std::uint64_t scene_hash = 0;                    // what a view checks the atlas against
  bool radiance = false;                           // cascade 0's radiance per direction written
  std::vector<std::uint64_t> probes, store_bytes;  // per cascade: probes placed, store (M_i)
  std::vector<StageTime> stages;   // in the order they ran (the file's writing last)
  double time_ms = 0;              // the whole bake, the file's writing included
  std::uint64_t memory_bytes = 0;  // peak working memory (BVH, stores, texels; not the scene)
  std::uint64_t rays = 0;
  std::uint64_t file_bytes = 0;
};

// Bakes the scene's light into its surface atlas (options.surface, bounces, threads, max_memory)
// and writes it to `path` (an EXR; docs/METHODS.md, "The atlas file"), atomically, with cascade
// 0's radiance per direction where `radiance` (what glossy queries read; Q0 channels of RGB).
// Refused up front, like render(): options out of range, fog, too little memory.
Expected<BakeResult> bake(const Scene& scene, const RenderOptions& options, const std::string& path,
                          bool radiance = true);

struct MethodInfo {
  Method method;
  const char* name;
  const char* title;  // in sentences: "the world-space probe grid"
  const char* summary;
  // The RenderOptions fields the method reads, named as messages name them ("spwi.merge"); the
  // command line refuses an option of another method by these.
  std::vector<std::string> options;
  bool gpu = false;  // has a GPU port
};
// Every 3D method, in the order of the Method enum.
std::vector<MethodInfo> methods();

// A parameter a render ran with, derived values filled in (--json's "parameters").
struct Parameter {
  std::string name;
  std::variant<bool, std::int64_t, std::uint64_t, double, std::string> value;
};
// The parameters of the method of `result` as it used them.
std::vector<Parameter> describe(const RenderResult& result);
// The same in a few words for a report's first line (", 6 cascades, t0 0.25, merge bilinear3d,
// sun direct"), starting with a comma.
std::string describe_line(const RenderResult& result);

const char* to_string(Method m);
const char* to_string(Device d);
const char* to_string(Aov a);
const char* to_string(SpwiMerge m);
const char* to_string(SpwiSun s);
const char* to_string(SpwiGather g);
const char* to_string(SsrcOffscreen o);
const char* to_string(SpecularQuery q);

}  // namespace penumbra::spaceland
