// Writing 3D results: linear PFM/EXR, and the display PNG of each kind of image.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "core/tone_map.hpp"
#include "io/image_io.hpp"
#include "io/path_util.hpp"
#include "penumbra/spaceland/io.hpp"

namespace penumbra::spaceland {

namespace {

// Range of the finite values of every channel (an empty range widens to 1).
void finite_range(const ImageRgb& img, float& lo, float& hi) {
  lo = std::numeric_limits<float>::infinity();
  hi = -lo;
  for (std::size_t i = 0; i < img.size(); ++i) {
    const float v = img.data()[i];
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (!(hi > lo)) hi = lo + 1;
}

}  // namespace

float auto_exposure(const ImageRgb& image, Aov aov) {
  if (aov != Aov::radiance && aov != Aov::emission) return 0;
  std::vector<float> lit;
  lit.reserve(std::size_t(image.width()) * image.height());
  const float* p = image.data();
  for (std::size_t i = 0; i < image.size(); i += 3) {
    const float m = luminance(p + i);
    if (m > 0 && std::isfinite(m)) lit.push_back(m);
  }
  return meter_exposure(lit, kAutoExposureKey);
}

ImageRgb8 display_picture(const ImageRgb& image, Aov aov, const DisplayOptions& display) {
  ImageRgb8 pic{image.width(), image.height(), std::vector<unsigned char>(image.size())};
  const float gain = std::exp2(display.exposure);
  float lo = 0, hi = 1;
  if (aov == Aov::depth || aov == Aov::position) finite_range(image, lo, hi);
  const float* p = image.data();
  const std::size_t w = std::size_t(image.width());
  parallel_for(image.height(), [&](int y) {
    for (std::size_t i = std::size_t(y) * w * 3, end = i + w * 3; i < end; i += 3) {
      for (std::size_t c = 0; c < 3; ++c) {
        const float v = p[i + c];
        float shown = 0;
        switch (aov) {
          case Aov::radiance:
          case Aov::emission:
            shown = io::linear_to_srgb(aces_fit(v * gain));
            break;
          case Aov::albedo:
            shown = io::linear_to_srgb(std::clamp(v, 0.0f, 1.0f));
            break;
          case Aov::normal:
            shown = std::clamp(0.5f + 0.5f * v, 0.0f, 1.0f);
            break;
          case Aov::depth:
            // Near is bright, far is dark, misses are black.
            shown = std::isfinite(v) ? 1 - 0.9f * (v - lo) / (hi - lo) : 0.0f;
            break;
          case Aov::position:
            shown = std::clamp((v - lo) / (hi - lo), 0.0f, 1.0f);
            break;
          case Aov::object: {
            // A distinct colour per object from a hash of its index; -1 (misses) black.
            const std::uint32_t h = std::uint32_t(std::int32_t(v) + 1) * 0x9E3779B1u;
            shown = v < 0 ? 0.0f : 0.25f + 0.75f * float((h >> (8 * c)) & 0xFF) / 255.0f;
            break;
          }
        }
        pic.rgb[i + c] = to_byte(std::clamp(shown, 0.0f, 1.0f));
      }
    }
  });
  return pic;
}

Status write_images(const std::vector<std::string>& paths, const ImageRgb& image, Aov aov,
                    const DisplayOptions& display) {
  return io::write_all(paths, [&](std::size_t i) -> Expected<io::StagedFile> {
    const std::string& path = paths[i];
    const std::string ext = io::lowercase_extension(path);
    if (ext == ".pfm") return io::stage_pfm(path, image);
    if (ext == ".exr") return io::stage_exr(path, image, std::string("3d ") + to_string(aov));
    if (ext == ".png") {
      const ImageRgb8 pic = display_picture(image, aov, display);
      return io::stage_png8(path, pic.width, pic.height, pic.rgb);
    }
    return Error{path + ": unsupported output format " +
                 (ext.empty() ? std::string("(no extension)") : "'" + ext + "'") +
                 " (supported: .pfm, .exr, .png)"};
  });
}

}  // namespace penumbra::spaceland
