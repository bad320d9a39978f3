// The public image functions: results out (linear PFM/EXR, display PNG), linear RGB in.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "core/parallel.hpp"
#include "io/display.hpp"
#include "io/image_io.hpp"
#include "io/path_util.hpp"
#include "penumbra/io.hpp"

namespace penumbra {
namespace {

// Krzysztof Narkowicz's fit of the ACES filmic curve, clamped to [0, 1].
float aces_fit(float x) {
  if (!(x > 0)) return 0;  // negatives and NaN show as black
  x = std::min(x, 1e4f);   // the curve is already 1 there; keeps infinities out of the ratio
  const float y = (x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f);
  return std::clamp(y, 0.0f, 1.0f);
}

unsigned char to_byte(float v) {
  return static_cast<unsigned char>(std::lround(v * 255.0f));
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
  return io::stage_png8(path, w, h, io::display_rgb8(fluence, &scene, display));
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

std::vector<unsigned char> io::display_rgb8(const ImageRgb& fluence, const Scene* scene,
                                            const DisplayOptions& display) {
  const float gain = std::exp2(display.exposure);
  const float inv_two_pi = 1.0f / (2.0f * std::numbers::pi_v<float>);
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

bool is_supported_output(const std::string& path) {
  const std::string ext = io::lowercase_extension(path);
  return ext == ".pfm" || ext == ".exr" || ext == ".png";
}

Status check_output(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path target(path);
  const std::filesystem::path dir = target.parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir, ec))
    return Error{path + ": cannot write into " + dir.string() + ": " +
                 std::make_error_code(std::errc::no_such_file_or_directory).message()};
  if (std::filesystem::is_directory(target, ec))
    return Error{path + ": " + std::make_error_code(std::errc::is_a_directory).message()};
  return {};
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

Status write_pictures(const std::vector<std::pair<std::string, ImageRgb8>>& files) {
  std::vector<std::string> paths;
  for (const auto& [path, picture] : files) {
    if (io::lowercase_extension(path) != ".png")
      return Error{path + ": pictures are written as PNG (use a .png file name)"};
    paths.push_back(path);
  }
  return io::write_all(paths, [&](std::size_t i) {
    const ImageRgb8& p = files[i].second;
    return io::stage_png8(paths[i], p.width, p.height, p.rgb);
  });
}

Expected<ImageRgb> read_rgb_image(const std::string& path) {
  auto raw = io::read_image(path);
  if (!raw) return raw.error();
  const io::RawImage& img = *raw;
  // Grey (1) and grey+alpha (2) expand to RGB; alpha (2, 4) is dropped.
  const bool grey = img.channels < 3;
  ImageRgb out(img.width, img.height);
  const std::size_t cells = std::size_t(img.width) * img.height;
  float* dst = out.data();
  for (std::size_t i = 0; i < cells; ++i) {
    const float* p = img.pixels.data() + i * img.channels;
    for (int c = 0; c < 3; ++c) {
      float v = p[grey ? 0 : c];
      if (img.integer_png) v = io::srgb_to_linear(v);  // PNG values are sRGB-encoded
      dst[i * 3 + c] = v;
    }
  }
  return out;
}

}  // namespace penumbra
