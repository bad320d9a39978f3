// The public file functions that know no scene: pictures out, linear RGB in, output checks.
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "io/image_io.hpp"
#include "io/path_util.hpp"
#include "penumbra/io.hpp"

namespace penumbra {

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
  // Outputs are renamed into place, which needs only the directory's permission: a file the
  // user could not write is refused here, as cp would refuse it. Root may write any file, so
  // for root a file with no write permission bit at all counts as protected.
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode)) {
    const bool protected_file = ::geteuid() == 0 ? (st.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)) == 0
                                                 : ::access(path.c_str(), W_OK) != 0;
    if (protected_file) {
      char mode[8];
      std::snprintf(mode, sizeof mode, "%04o", unsigned(st.st_mode & 07777));
      return Error{path + ": the file is write-protected (mode " + mode +
                   "); not replacing it (make it writable or remove it first)"};
    }
  }
  return {};
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

Expected<ImageRgb> read_rgb_image(const std::string& path, std::uint64_t max_bytes) {
  auto raw = io::read_image(path, 0, 0, max_bytes);
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
