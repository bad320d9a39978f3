// `--method surface`: bake the scene's light into the surface atlas (cascades.hpp), then shade
// the camera's first hits from it. docs/METHODS.md, "Surface radiance cascades".
#pragma once

#include <cstdint>
#include <string>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"
#include "spaceland/solve.hpp"

namespace penumbra::spaceland::atlas {

// The options' ranges, fields named as in RenderOptions (`surface.directions`).
Status check_options(const SurfaceOptions& o);
// What it cannot carry: fog. (Glossy materials read cascade 0's radiance per direction.)
Status check_scene(const Scene& scene);
// Its working memory at most: the bake's (bake_bytes) for the texels the atlas will hold, its
// chart rectangles and gutters counted at 3x the surfaces' texels (measured: 1.4x-3.1x on the
// Cornell box, the bunny and the engine).
// With `radiance` or a glossy material in the scene, cascade 0's radiance per direction kept (and
// written by a bake) too; with an atlas file to
// view from, nothing here (reading it is held to the memory left, from its header).
std::uint64_t working_bytes(const Scene& scene, const SurfaceOptions& o, bool radiance = false);
// A bake for `penumbra bake`: `scene` is what the cascades trace (a dimmed copy of `given` where
// light_exponent > 0: the file holds the light at that scale and says so), `given` what the file's
// hash is of.
struct FileBake {
  const Scene& scene;
  const Scene& given;
  const RayScene& rays;
  const SurfaceOptions& o;
  int bounces = 1;
  int light_exponent = 0;
  bool radiance = true;
  std::uint64_t max_bytes = 0;
};
// Bakes and writes the atlas file (file.hpp) at `path`, filling in what it made and cost.
Status bake_file(const FileBake& b, const std::string& path, BakeResult& result);

// Bakes (or reads o.atlas), then shades every visible pixel: its emission, plus its diffuse lobe's
// albedo / pi times the atlas's irradiance there (sky, emitters, bounces), a glossy surface's
// specular lobe over the kept radiance (Baked::lobe_at) and the sun's shadow rays at the pixel.
// `used` receives the texel size, interval and cascade count it derived.
Expected<ImageRgb> render(const SolveContext& ctx, const SurfaceOptions& o, SolveReport& report,
                          SurfaceOptions& used);

}  // namespace penumbra::spaceland::atlas
