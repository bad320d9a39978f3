// The public image functions: results out (linear PFM/EXR, display PNG), linear RGB in.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <system_error>
#include <vector>

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
  const float gain = std::exp2(display.exposure);
  const float inv_two_pi = 1.0f / (2.0f * std::numbers::pi_v<float>);
  std::vector<unsigned char> rgb(cells * 3);
  const float* f = fluence.data();
  for (std::size_t i = 0; i < cells; ++i) {
    const float a = scene.opacity[i];
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t k = i * 3 + c;
      const float m = f[k] * inv_two_pi;  // mean radiance over directions
      // Opaque cells show what they emit and reflect; clear cells show the light passing.
      const float shown = a * (scene.emission[k] + scene.albedo[k] * m) + (1 - a) * m;
      rgb[k] = to_byte(io::linear_to_srgb(aces_fit(shown * gain)));
    }
  }
  return io::stage_png8(path, w, h, rgb);
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
  // Targets that cannot be renamed onto are refused before anything is written.
  for (const std::string& path : paths)
    if (Status s = check_output(path); !s) return s;
  std::vector<io::StagedFile> staged;
  auto discard_from = [&](std::size_t first) {
    for (std::size_t i = first; i < staged.size(); ++i) io::discard(staged[i]);
  };
  for (const std::string& path : paths) {
    Expected<io::StagedFile> f = stage_image(path, fluence, scene, display);
    if (!f) {
      discard_from(0);
      return f.error();
    }
    staged.push_back(*f);
  }
  for (std::size_t i = 0; i < staged.size(); ++i) {
    if (Status s = io::publish(staged[i]); !s) {
      discard_from(i + 1);
      return s;
    }
  }
  return {};
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
