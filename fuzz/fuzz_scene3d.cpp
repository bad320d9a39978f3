// libFuzzer target: the 3D scene loader (parse_scene) on arbitrary text; a scene it accepts must
// pass check_scene, and small ones are rendered (Embree's BVH, the G-buffer and one path-traced
// sample of two bounces), which must succeed, and by the probe grid on coarse voxels, which
// may refuse but must give a finite image. docs/RELIABILITY.md.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"

namespace {

using namespace penumbra::spaceland;
using penumbra::Expected;

// Rendering costs pixels x triangles at worst; only small scenes are rendered (a big one is a
// legitimate scene whose slowness is no finding).
constexpr long long kMaxPixels = 32 * 32;
constexpr std::size_t kMaxTriangles = 20000;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // Mesh paths resolve against the working directory, where scripts/fuzz.sh puts tiny meshes.
  LoadOptions load;
  load.max_memory = std::uint64_t(256) << 20;
  Expected<Scene> scene = parse_scene(text, "fuzz.json", load);
  if (!scene) return 0;
  if (!check_scene(*scene)) std::abort();  // parse_scene validated it
  std::size_t triangles = 0;
  for (const TriangleMesh& m : scene->meshes) triangles += m.triangles.size();
  if (static_cast<long long>(scene->camera.width) * scene->camera.height > kMaxPixels ||
      triangles > kMaxTriangles)
    return 0;
  RenderOptions options;
  options.pt.spp = 1;
  options.bounces = 2;
  options.threads = 1;
  options.max_memory = std::uint64_t(512) << 20;
  // Light past what floats hold at these bounces is refused by design (a documented refusal).
  if (!check_brightness(*scene, options)) return 0;
  Expected<RenderResult> r = render(*scene, options);
  // A valid small scene must render, unless its answer is so near the float range that the
  // path tracer's spread passes it (refused, by design).
  if (!r && r.error().message.find("passes the float range") == std::string::npos) std::abort();
  if (!r) return 0;
  // The probe grid on the same scene, coarse (the voxel derived from a small memory limit, a
  // few thousand voxels): voxelising arbitrary geometry, fog and the sun through two bounces. It
  // may refuse (memory); what it renders must be finite.
  options.method = Method::grid;
  options.grid.directions = 4;
  options.max_memory = std::uint64_t(8) << 20;
  Expected<RenderResult> g = render(*scene, options);
  if (g)
    for (std::size_t k = 0; k < g->radiance.size(); ++k)
      if (!std::isfinite(g->radiance.data()[k])) std::abort();
  return 0;
}
