// What every 3D method's solve is handed and what it reports besides its image: the method table
// (method.hpp) hands each solver this and its own options, never the whole RenderOptions.
#pragma once

#include <any>
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/progress.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/gbuffer.hpp"
#include "spaceland/temporal.hpp"

namespace penumbra::spaceland {

class RadianceCache;

// What a Renderer keeps for a method between frames of one scene (the surface method's atlas):
// the method stores its own type in `method` with what it was made from, and checks that itself.
struct Kept {
  std::uint64_t scene_key = 0;     // Renderer::scene_key of the scene it was made for
  std::uint64_t geometry_key = 0;  // and of this frame's scene without its sky and sun
  std::any method;
};

// The scene, its ray tracer, the camera's first hits, and what every method shares.
struct SolveContext {
  const Scene& scene;
  const RayScene& rays;
  const GBuffer& g;
  int bounces = 1;  // 1: direct light only
  std::uint64_t max_memory = 0;
  int sun_rays = 16;  // RenderOptions::sun_rays
  // The scene as given, where `scene` is its dimmed copy (light at 2^-light_exponent, scaled back
  // after the solve; spaceland/brightness.hpp): what a file made for the scene is checked against.
  const Scene* given = nullptr;
  int light_exponent = 0;
  // Later bounces' light at the surfaces, for a method that does not follow them itself (the
  // dispatcher builds it when bounces > 1); null otherwise.
  const RadianceCache* cache = nullptr;
  // Progressive methods call `progress` between passes and stop when `cancel` turns true.
  const std::function<void(const RenderProgress&)>* progress = nullptr;
  const std::atomic<bool>* cancel = nullptr;
  // A Renderer's store for what does not depend on the camera; null in a single render().
  Kept* kept = nullptr;
  // Temporal accumulation's frame index in its history, 0 in a single render(): ssrc turns its
  // screen directions by temporal::jitter(frame) of a cascade-0 direction; spwi moves its probe
  // lattice by the frame's point (spwi::shift_lattice).
  std::uint64_t frame = 0;
  // Temporal accumulation asks for SolveReport::exact.
  bool want_exact = false;
  // RenderOptions::temporal.grid_slabs, in a Renderer (0 in a single render()).
  std::uint64_t grid_slabs = 0;
};

// What a solve reports besides the image.
struct SolveReport {
  std::vector<StageTime> stages;   // in the order they ran
  std::uint64_t rays = 0;          // rays traced (not the G-buffer's)
  std::uint64_t samples = 0;       // per pixel, for progressive methods
  std::uint64_t memory_bytes = 0;  // the method's working memory
  std::uint64_t voxel_bytes = 0;   // the voxels' share of it (the probe grid)
  bool cancelled = false;
  std::vector<std::string> warnings;  // what the user should know about the result
  temporal::Exact exact;              // where ctx.want_exact (temporal accumulation's frames)
  // The grid's solve under way, a slab at a time (RenderResult's).
  std::uint64_t grid_slabs_done = 0, grid_slabs = 0;
};

// The refusal of a method that cannot carry fog (its check_scene): "<method> cannot carry fog:
// the scene has N medium box(es); use <instead>".
inline Status refuse_fog(const Scene& scene, const char* method, const char* instead) {
  if (scene.media.empty()) return {};
  return Error{std::string(method) + " cannot carry fog: the scene has " +
               std::to_string(scene.media.size()) + " medium box(es); use " + instead};
}

}  // namespace penumbra::spaceland
