// Embedding libpenumbra: build a scene in code, render it, write a picture, check the result.
//
//   render_in_code [output.png|.exr|.pfm]     (default: render_in_code.png)
//
// The library throws nothing across its API: every call returns a Status or an Expected<T>,
// which this program checks, printing the message and returning 1 on failure.
#include <cmath>
#include <cstdio>
#include <string>

#include "penumbra/penumbra.hpp"

namespace {

// Grid size in cells; coordinates below are in cells, y pointing down.
constexpr int kWidth = 160;
constexpr int kHeight = 120;

int fail(const std::string& what) {
  std::fprintf(stderr, "render_in_code: %s\n", what.c_str());
  return 1;
}

penumbra::flatland::Shape disk_light(float x, float y, float radius, penumbra::Rgb radiance) {
  penumbra::flatland::Shape s;
  s.geometry = penumbra::flatland::Circle{{x, y}, radius};
  s.material.emission = radiance;  // opacity defaults to 1: an opaque, glowing disk
  return s;
}

penumbra::flatland::Shape wall(float x, float y, float w, float h) {
  penumbra::flatland::Shape s;
  s.geometry = penumbra::flatland::Box{{x, y}, {w, h}, 0.0f};
  return s;  // default material: opaque and black, so it only casts shadows
}

// Mean of the three channels of the fluence at cell (x, y).
float fluence_at(const penumbra::ImageRgb& f, int x, int y) {
  const penumbra::Rgb c = f.at(x, y);
  return (c.r + c.g + c.b) / 3.0f;
}

}  // namespace

int main(int argc, char** argv) {
  // One optional argument, the output file; anything that looks like an option gets the usage
  // (rather than becoming a file named "--help").
  const std::string output = argc > 1 ? argv[1] : "render_in_code.png";
  if (argc > 2 || (!output.empty() && output[0] == '-')) {
    const bool help = argc == 2 && (output == "-h" || output == "--help");
    std::fprintf(help ? stdout : stderr, "usage: render_in_code [output.png|.exr|.pfm]\n");
    return help ? 0 : 2;
  }

  // 1. Describe the scene: the same document a JSON scene file holds (docs/scene-format.md).
  penumbra::flatland::SceneDesc desc;
  desc.width = kWidth;
  desc.height = kHeight;
  desc.environment = {0.02f, 0.02f, 0.03f};  // dim blue-grey light from outside the grid
  desc.source = "render_in_code";            // names the scene in error messages
  // Two coloured lights on the left of a vertical wall at x = 100...
  desc.shapes.push_back(disk_light(40, 35, 6, {6.0f, 2.0f, 1.0f}));  // warm
  desc.shapes.push_back(disk_light(40, 85, 6, {1.0f, 2.0f, 6.0f}));  // cool
  // ...made of two boxes with a gap between y = 50 and y = 70 that lets light through.
  desc.shapes.push_back(wall(100, 25, 4, 50));  // covers y in [0, 50]
  desc.shapes.push_back(wall(100, 95, 4, 50));  // covers y in [70, 120]

  // 2. Validate and rasterise it into cells.
  penumbra::Expected<penumbra::flatland::Scene> scene = penumbra::flatland::build_scene(desc);
  if (!scene) return fail(scene.error().message);

  // 3. Render with the default options: radiance cascades with the bilinear fix, all cores.
  penumbra::Expected<penumbra::flatland::RenderResult> result =
      penumbra::flatland::render(*scene, penumbra::flatland::RenderOptions{});
  if (!result) return fail(result.error().message);
  std::printf("method %s: %.1f ms, %.1f MiB of working memory, %d cascades\n",
              penumbra::flatland::to_string(result->options.method), result->time_ms,
              double(result->memory_bytes) / (1 << 20), result->options.rc.cascades);

  // 4. Write the fluence; the extension picks the format (PNG is tone-mapped for display).
  if (penumbra::Status s = penumbra::flatland::write_image(output, result->fluence, *scene); !s)
    return fail(s.error().message);
  std::printf("wrote %s\n", output.c_str());

  // 5. Check the picture makes sense: a cell beside a light must be brighter than one in the
  // wall's shadow, and the gap must let more light through than the wall does.
  const penumbra::ImageRgb& f = result->fluence;
  const float beside_light = fluence_at(f, 50, 35);  // 4 cells right of the warm disk's edge
  const float behind_gap = fluence_at(f, 130, 60);   // in line with the gap
  const float behind_wall = fluence_at(f, 130, 10);  // both lights hidden by the upper wall
  std::printf("fluence: beside a light %.3f, behind the gap %.3f, behind the wall %.3f\n",
              beside_light, behind_gap, behind_wall);
  for (float v : {beside_light, behind_gap, behind_wall})
    if (!std::isfinite(v) || v < 0) return fail("fluence is negative or not finite");
  if (!(beside_light > 10 * behind_wall))
    return fail("expected the cell beside a light to be far brighter than behind the wall");
  if (!(behind_gap > 2 * behind_wall))
    return fail("expected the gap in the wall to let light through");
  return 0;
}
