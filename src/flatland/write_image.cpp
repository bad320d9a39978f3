// Writing 2D results: linear PFM/EXR, and the display PNG of fluence with the scene's emitters.
#include <cmath>
#include <string>
#include <vector>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "core/tone_map.hpp"
#include "io/image_io.hpp"
#include "io/path_util.hpp"
#include "penumbra/flatland/io.hpp"

namespace penumbra::flatland {
namespace {

std::vector<unsigned char> display_rgb8(const ImageRgb& fluence, const Scene* scene,
                                        const DisplayOptions& display) {
  const float gain = std::exp2(display.exposure);
  const float inv_two_pi = 1.0f / (2.0f * float(kPi));
  const std::size_t cells = std::size_t(fluence.width()) * fluence.height();
  std::vector<unsigned char> rgb(cells * 3);
  const float* f = fluence.data();
  const std::size_t w = std::size_t(fluence.width());
  parallel_for(fluence.height(), [&](int y) {
    for (std::size_t i = std::size_t(y) * w, end = i + w; i < end; ++i) {
      const float a = scene ? scene->opacity[i] : 0.0f;
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t k = i * 3 + c;
        const float m = f[k] * inv_two_pi;  // mean radiance over directions
        // Opaque cells show what they emit and reflect; clear cells show the light passing.
        const float shown =
            scene ? a * (scene->emission[k] + scene->albedo[k] * m) + (1 - a) * m : m;
        rgb[k] = to_byte(io::linear_to_srgb(aces_fit(shown * gain)));
      }
    }
  });
  return rgb;
}

Expected<io::StagedFile> stage_display_png(const std::string& path, const ImageRgb& fluence,
                                           const Scene& scene, const DisplayOptions& display) {
  const int w = fluence.width(), h = fluence.height();
  if (scene.width != w || scene.height != h) {
    return Error{path + ": fluence is " + std::to_string(w) + " x " + std::to_string(h) +
                 " but the scene is " + std::to_string(scene.width) + " x " +
                 std::to_string(scene.height)};
  }
  const std::size_t cells = scene.cells();
  if (scene.emission.size() != cells * 3 || scene.opacity.size() != cells ||
      scene.albedo.size() != cells * 3) {
    return Error{path + ": scene layers do not match its " + std::to_string(w) + " x " +
                 std::to_string(h) + " grid"};
  }
  return io::stage_png8(path, w, h, display_rgb8(fluence, &scene, display));
}

Expected<io::StagedFile> stage_image(const std::string& path, const ImageRgb& fluence,
                                     const Scene& scene, const DisplayOptions& display) {
  const std::string ext = io::lowercase_extension(path);
  if (ext == ".pfm") return io::stage_pfm(path, fluence);
  if (ext == ".exr") return io::stage_exr(path, fluence);
  if (ext == ".png") return stage_display_png(path, fluence, scene, display);
  return Error{path + ": unsupported output format " +
               (ext.empty() ? std::string("(no extension)") : "'" + ext + "'") +
               " (supported: .pfm, .exr, .png)"};
}

}  // namespace

ImageRgb8 display_picture(const ImageRgb& fluence, const Scene* scene,
                          const DisplayOptions& display) {
  return {fluence.width(), fluence.height(), display_rgb8(fluence, scene, display)};
}

Status write_image(const std::string& path, const ImageRgb& fluence, const Scene& scene,
                   const DisplayOptions& display) {
  return write_images({path}, fluence, scene, display);
}

Status write_images(const std::vector<std::string>& paths, const ImageRgb& fluence,
                    const Scene& scene, const DisplayOptions& display) {
  return io::write_all(
      paths, [&](std::size_t i) { return stage_image(paths[i], fluence, scene, display); });
}

}  // namespace penumbra::flatland
