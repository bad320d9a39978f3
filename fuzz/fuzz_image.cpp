// libFuzzer target: the image readers (io::read_image: PNG through stb, EXR through OpenEXR,
// PFM by hand) on arbitrary bytes. The readers take paths, so each input is written to a
// temporary file whose extension follows its magic bytes. docs/RELIABILITY.md.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "io/image_io.hpp"

namespace {

// PNG and EXR by their signatures; anything else goes to the PFM reader, whose header is text.
const char* extension(const std::uint8_t* data, std::size_t size) {
  static constexpr std::uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  static constexpr std::uint8_t kExr[4] = {0x76, 0x2f, 0x31, 0x01};
  if (size >= sizeof kPng && std::memcmp(data, kPng, sizeof kPng) == 0) return ".png";
  if (size >= sizeof kExr && std::memcmp(data, kExr, sizeof kExr) == 0) return ".exr";
  return ".pfm";
}

std::string temp_path(const char* ext) {
  return (std::filesystem::temp_directory_path() /
          ("penumbra_fuzz_image_" + std::to_string(::getpid()) + ext))
      .string();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = temp_path(extension(data, size));
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) std::abort();

  penumbra::Expected<penumbra::io::RawImage> img = penumbra::io::read_image(path);
  if (img) {
    const penumbra::io::RawImage& r = *img;
    if (r.width < 1 || r.height < 1 || r.channels < 1 || r.channels > 4 ||
        r.pixels.size() != std::size_t(r.width) * r.height * r.channels)
      std::abort();
    // A layer reads with the grid's size expected: the same image must read again.
    if (!penumbra::io::read_image(path, r.width, r.height)) std::abort();
  }
  std::remove(path.c_str());
  return 0;
}
