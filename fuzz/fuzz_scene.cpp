// libFuzzer target: the 2D scene loader (parse_scene) on arbitrary text, then the writer round
// trip and, for small scenes, the rasteriser (build_scene). docs/RELIABILITY.md.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <type_traits>
#include <variant>

#include "penumbra/flatland/scene.hpp"

namespace {

using namespace penumbra::flatland;
using penumbra::Expected;

// The guard: rasterising costs about cells x (shapes + polygon points) x 256 samples at shape
// edges, so only scenes this small are built. The parser still sees every input; a grid of
// 16384^2 or thousands of shapes is a legitimate scene whose slowness is no finding, and the
// fuzzer should not spend its time there.
constexpr long long kMaxCells = 64 * 64;
constexpr std::size_t kMaxShapes = 32;
constexpr std::size_t kMaxPolygonPoints = 128;

bool small_enough(const SceneDesc& d) {
  if (static_cast<long long>(d.width) * d.height > kMaxCells) return false;
  if (d.shapes.size() > kMaxShapes) return false;
  std::size_t points = 0;
  for (const Shape& s : d.shapes)
    if (const auto* p = std::get_if<Polygon>(&s.geometry)) points += p->points.size();
  return points <= kMaxPolygonPoints;
}

bool same_bits(float a, float b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// scene_json promises parse_scene gives back the grid, environment and shapes bit for bit.
void check_round_trip(const SceneDesc& d) {
  Expected<SceneDesc> back = parse_scene(scene_json(d), "round-trip.json");
  if (!back) std::abort();
  const SceneDesc& b = *back;
  if (b.width != d.width || b.height != d.height || b.shapes.size() != d.shapes.size())
    std::abort();
  const penumbra::Rgb &e0 = d.environment, &e1 = b.environment;
  if (!same_bits(e0.r, e1.r) || !same_bits(e0.g, e1.g) || !same_bits(e0.b, e1.b)) std::abort();
  // Re-writing the parsed copy must give the same text: a cheap whole-document comparison.
  if (scene_json(b) != scene_json(d)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // Relative layer paths resolve against the working directory, where scripts/fuzz.sh puts
  // tiny layer images (layers/).
  Expected<SceneDesc> desc = parse_scene(text, "fuzz.json");
  if (!desc) return 0;
  // The writer writes layer file names, not decoded layers: only a scene without them can
  // come back whole.
  if (!desc->layers.emission && !desc->layers.opacity && !desc->layers.albedo)
    check_round_trip(*desc);
  if (!small_enough(*desc)) return 0;
  Expected<Scene> scene = build_scene(*desc);
  if (!scene) std::abort();  // parse_scene validated it: building must not fail
  if (scene->emission.size() != scene->cells() * 3 || scene->opacity.size() != scene->cells())
    std::abort();
  return 0;
}
