// Writing 2D results: linear PFM/EXR, and the display PNG of fluence with the scene's emitters.
#include <algorithm>
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

// Unlit walls are black like the dark around them, so a wall in the dark would be invisible:
// with DisplayOptions::show_walls, non-emitting walls and fog get a dim floor of their albedo's
// colour (0.3 of it for a wall, less for thin fog).
void show_walls(const Scene& s, std::vector<unsigned char>& rgb) {
  parallel_for(s.height, [&](int y) {
    for (std::size_t i = std::size_t(y) * s.width, end = i + s.width; i < end; ++i) {
      const float a = s.opacity[i];
      const float* le = &s.emission[3 * i];
      if (a <= 0 || le[0] + le[1] + le[2] > 0) continue;
      const float k = a >= 1 ? 0.3f : 0.3f * std::min(1.0f, 5 * a);
      for (int c = 0; c < 3; ++c) {
        const float floor = 255 * k * (0.25f + 0.75f * s.albedo[3 * i + c]);
        unsigned char& v = rgb[3 * i + c];
        v = std::max(v, static_cast<unsigned char>(floor));
      }
    }
  });
}

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
  if (scene && display.show_walls) show_walls(*scene, rgb);
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
  if (ext == ".exr") return io::stage_exr(path, fluence, "2d fluence");
  if (ext == ".png") return stage_display_png(path, fluence, scene, display);
  return Error{path + ": unsupported output format " +
               (ext.empty() ? std::string("(no extension)") : "'" + ext + "'") +
               " (supported: .pfm, .exr, .png)"};
}

}  // namespace

float auto_exposure(const ImageRgb& fluence, const Scene* scene) {
  const std::size_t cells = std::size_t(fluence.width()) * fluence.height();
  const bool layers =
      scene && scene->opacity.size() == cells && scene->emission.size() == 3 * cells;
  const float* f = fluence.data();
  std::vector<float> lit;
  lit.reserve(cells);
  for (std::size_t i = 0; i < cells; ++i) {
    if (layers) {
      const float* le = &scene->emission[3 * i];
      if (scene->opacity[i] >= 1 || le[0] + le[1] + le[2] > 0) continue;
    }
    const float m = luminance(f + 3 * i) * float(1 / (2 * kPi));  // mean radiance, as shown
    if (m > 0 && std::isfinite(m)) lit.push_back(m);
  }
  return meter_exposure(lit, kAutoExposureKey);
}

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
