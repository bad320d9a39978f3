// Running a method on a scene: options in, fluence and timings out.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/image.hpp"
#include "penumbra/progress.hpp"

namespace penumbra::flatland {

enum class Method {
  rc,   // radiance cascades (seed 001, seed 002)
  pt,   // the reference path tracer: converges to the exact fluence of the cell grid
  hrc,  // holographic radiance cascades (seed 004)
};

// How a ray of cascade n continues into cascade n+1 when merging.
enum class MergeFix {
  bilinear,  // "bilinear fix": trace to each of the 4 upper probes, merge, then weight
  none,      // "vanilla": merge with the bilinear interpolation of the 4 upper probes
  nearest,   // merge with the nearest upper probe only (blocky; for teaching)
};

// Flatland radiance cascades (seed 001 sections 2-3, seed 002). See docs/METHODS.md.
struct RcOptions {
  int probe_spacing = 1;  // s0: cascade-0 probe spacing in cells; cascade n uses s0 * 2^n
  int directions = 4;     // Q0: directions of a cascade-0 probe
  int branching = 4;      // angular branching per cascade: 4 or 2
  float interval = 4.0f;  // t0: length of the cascade-0 interval [0, t0], in cells
  int cascades = 0;       // 0: enough that the last interval reaches past the grid diagonal
  MergeFix fix = MergeFix::bilinear;
  bool preaverage = false;  // trace a 2x2 sub-probe neighbourhood and store the average
  bool extend = false;      // build long intervals by extending a short traced one (eq. 16)
  float extend_length = 8;  // length traced before extension doubles it, in cells
};

// Precision of stored intervals.
enum class Storage {
  f32,  // 32-bit floats
  f16,  // 16-bit floats (half the memory; brighter scenes are rendered at a scaled light)
};

// What a 45-degree ray of HRC's traced levels does at a cell corner it passes through, between
// two cells it does not enter (docs/METHODS.md).
enum class Corners {
  half,   // each of the two cells that is opaque stops half of the ray (the mean of the ray
          // nudged off the corner to either side)
  walls,  // only two opaque cells stop it (a wall meeting at corners), one opaque cell none
};

// Holographic radiance cascades (seed 004 section 4). See docs/METHODS.md.
struct HrcOptions {
  Storage storage = Storage::f32;  // of the acceleration structure T and the cascades R
  bool cross_blur = true;          // the 1-cell cross blur (eq. 21)
  // Blur the whole fluence, the near segment included, as eq. 21 is written (off: blur only the
  // light arriving from beyond the near segment, so that a cell's own medium and the cell beside
  // it stay sharp: the rims of lights, docs/QUALITY.md).
  bool blur_near = false;
  // Merge the transport from a cell's centre to the probe the paper reads, R_0([x+1, y]), in
  // front of it (off: the paper's formula, which leaves a cell's own medium out of its fluence).
  bool near_segment = true;
  Corners corners = Corners::half;
  // The fan: some cells gather through rays instead of their quadrants' R_0 reads, from the
  // cell's centre, 2 rays per cone of cascade `wall_fan` (2^wall_fan cones per quadrant) to the
  // first of that cascade's probe columns more than half its spacing ahead, each merged with its
  // cone of R there. A wall cell reads its quadrants through the cell beside it, which leaves
  // edges lit at a grazing angle through anti-aliased cells dark, and near a light's rim the
  // cones of cascades 0..2 are coarse for its edge (docs/QUALITY.md). 0: no fan, every cell
  // reads its quadrants (the paper's formula). 1..8; a grid with fewer cascades uses its
  // highest below the environment.
  int wall_fan = 3;
  // How many cells the fan gathers: ceil(fan_share * cells) but at least 512 (or every cell of a
  // smaller grid), whatever the scene holds, so the fan costs the same on every scene of a
  // grid size. The cells taken are, in this order: lit
  // wall cells (opaque, with a cell that is not among their 8 neighbours) and lights' rims (a
  // cell of the scene's own emission with a cell that emits nothing among its 8 neighbours);
  // the cells that are not opaque within `near_fan` cells of a rim (along x and y), nearest
  // first; the other open cells; the cells inside walls. Within one rank in row order, so where the
  // budget ends inside a rank (a scene of many small lights) the first rows have the fan and the
  // last do not. In (0, 1].
  float fan_share = 1.0f / 64.0f;
  // How far from a light's rim (in cells, along x and y) the fan ranks open cells by their
  // distance; 0..16. Farther, its rays do no better than the cascades (docs/QUALITY.md).
  int near_fan = 2;
  // Eqs. 15-17 at an even probe column: the weight of the cones of R_{n+1} at the column's own
  // probe, the rest going to the merges along the doubled edges; in [0, 1]. The seed's mean is
  // 1/2. Merges along edges represent a cone by its edges, so each parity of column sees light
  // pushed towards its cones' edges: quadrant axes too dark and diagonals too bright around
  // lights; a larger weight shifts even columns less (docs/METHODS.md, "The edge bias").
  float even_weight = 0.575f;
};
inline constexpr int kMaxWallFan = 8;   // HrcOptions::wall_fan
inline constexpr int kMaxNearFan = 16;  // HrcOptions::near_fan

// Where the path tracer's directions come from.
enum class Sampler {
  r1,      // golden-ratio (R1) sequence with a per-cell random rotation (Cranley-Patterson)
  random,  // independent uniform numbers per cell and sample (error falls as 1/sqrt(spp))
};

// The reference path tracer (seed 004 section 5). See docs/METHODS.md.
struct PtOptions {
  int spp = 64;        // samples (directions) per cell; with `seconds`, the most to take
                       // (0: no limit)
  double seconds = 0;  // > 0: add samples until this much time has passed
  bool nee = false;    // next event estimation: also aim at emitting regions, combined by MIS
  Sampler sampler = Sampler::r1;
  std::uint64_t seed = 0;  // changes every random number; same seed, same result
};

// Reported between passes of progressive methods.
using penumbra::RenderProgress;

// Where a method runs.
enum class Device {
  cpu,    // this machine's cores
  gpu,    // Vulkan compute on the best device, a CPU driver (lavapipe) included; an error if none
  auto_,  // a hardware GPU when there is one and the method runs there, the CPU otherwise
};

struct RenderOptions {
  Method method = Method::rc;
  // The GPU runs RC (no interval extension) and HRC, any bounces (docs/GPU.md).
  Device device = Device::cpu;
  RcOptions rc;
  PtOptions pt;
  HrcOptions hrc;
  int bounces = 1;  // 1: direct light only; N: N-1 more diffuse bounces
  int threads = 0;  // 0: all hardware threads
  // rc and pt (hrc traces only rays a few cells long and builds neither):
  bool distance_field = true;  // jump over empty space (same answer, faster); off: plain DDA
  bool blocks = true;          // skip empty 8x8 blocks (two-level DDA; same answer, faster)
  std::uint64_t max_memory = std::uint64_t(8) << 30;  // refuse work whose memory need is larger
  // Progressive methods (pt) call this from the calling thread between passes.
  std::function<void(const RenderProgress&)> progress;
  // When set to true, progressive methods stop after the current pass and return what they have
  // (RenderResult::cancelled); others ignore it.
  const std::atomic<bool>* cancel = nullptr;
};

using penumbra::StageTime;

struct RenderResult {
  ImageRgb fluence;                    // linear RGB fluence at every cell centre
  std::vector<StageTime> stages;       // in the order they ran
  double time_ms = 0;                  // computation only, no file I/O
  std::uint64_t memory_bytes = 0;      // peak working memory of the method (not the scene)
  std::uint64_t intervals = 0;         // ray intervals traced (all bounces; pt: rays)
  std::uint64_t samples = 0;           // pt: samples per cell in the result
  bool cancelled = false;              // pt: stopped early through RenderOptions::cancel
  RenderOptions options;               // the options used, with derived values filled in
  std::string device = "cpu";          // what ran it: "cpu", or the GPU's name
  std::uint64_t gpu_memory_bytes = 0;  // on a GPU: device memory the render keeps allocated
  std::uint64_t uploaded_bytes = 0;    // on a GPU: bytes copied to it (only what changed)
};

// Checks options against a grid size: ranges, combinations, and hierarchies too deep to build.
Status check_options(int width, int height, const RenderOptions& options);

// Working memory the method would need, known before anything is allocated (the largest value
// when the options are invalid).
std::uint64_t estimate_memory(const Scene& scene, const RenderOptions& options);
std::uint64_t estimate_memory(int width, int height, const RenderOptions& options);

// Bytes of a rasterised Scene of this size (emission, opacity, albedo).
std::uint64_t scene_bytes(int width, int height);

// Refuses, before anything is allocated, work whose memory need exceeds options.max_memory: the
// method's working memory, plus the rasterised scene when `with_scene` (a program that has not
// built the scene yet).
Status check_memory(int width, int height, const RenderOptions& options, bool with_scene);

// Refuses a scene whose fluence a float cannot hold: radiance is at most the brightest emission
// or environment L times the bounces, fluence at most 2 pi times that. The message names the
// file and the JSON path of the brightest value. render() checks a rasterised scene the same way
// (naming the cell), and renders a scene too bright for a method's storage at a power-of-two
// fraction of its light, scaling the result back exactly.
Status check_brightness(const SceneDesc& desc, const RenderOptions& options);

// Runs the method. Refuses up front (Error, nothing allocated) when options are invalid, the
// memory estimate exceeds options.max_memory, or the scene is too bright (check_brightness); never
// returns a fluence that is not finite.
Expected<RenderResult> render(const Scene& scene, const RenderOptions& options);

// Renders again and again with the same buffers: a program that renders every frame (the
// painter) keeps one, so that only its first frame allocates and first touches the working
// memory. Same results as render(); it holds its memory until destroyed. One thread at a time.
class Renderer {
 public:
  Renderer();
  ~Renderer();
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;
  Expected<RenderResult> render(const Scene& scene, const RenderOptions& options);
  struct State;

 private:
  std::unique_ptr<State> state_;
};

// A method as the command line lists it: its name, a line of help, and whether it has a GPU port.
struct MethodInfo {
  Method method;
  const char* name;
  const char* summary;
  bool gpu;
  bool skips_empty_space;  // reads RenderOptions::distance_field and blocks
};
// Every method, in the order of the Method enum (the dispatcher's table, docs/ARCHITECTURE.md).
std::vector<MethodInfo> methods();

const char* to_string(Method m);
const char* to_string(MergeFix f);
const char* to_string(Sampler s);
const char* to_string(Storage s);
const char* to_string(Corners c);
const char* to_string(Device d);

}  // namespace penumbra::flatland
