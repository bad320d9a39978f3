// libFuzzer target: reading a baked surface atlas (`render --method surface --atlas`) from
// arbitrary bytes, written to a temporary .exr, for the scene of atlas_scene.hpp, with a memory
// limit of 32 MiB (the seeds take kilobytes). docs/RELIABILITY.md.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "atlas_scene.hpp"
#include "spaceland/atlas/file.hpp"

namespace {

bool light(const penumbra::Rgb& c) {
  return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b) && c.r >= 0 && c.g >= 0 &&
         c.b >= 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const penumbra::spaceland::Scene scene = atlas_fuzz_scene();
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("penumbra_fuzz_atlas_" + std::to_string(::getpid()) + ".exr"))
                               .string();
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) std::abort();

  namespace atlas = penumbra::spaceland::atlas;
  atlas::Record record;
  const penumbra::Expected<atlas::Baked> b =
      atlas::read_atlas(path, scene, std::uint64_t(32) << 20, record);
  if (b) {
    // What a view reads is whole and is light.
    const std::size_t n = std::size_t(b->atlas.width) * std::size_t(b->atlas.height);
    if (b->texels.size() != n || b->front.size() != n || b->back.size() != n ||
        b->sun_front.size() != n || b->sun_back.size() != n)
      std::abort();
    if (b->side0 * b->side0 != (b->side0 > 0 ? record.directions : 0) ||
        b->radiance.size() != n * std::size_t(b->side0) * std::size_t(b->side0))
      std::abort();
    for (std::size_t k = 0; k < n; ++k)
      if (!light(b->front[k]) || !light(b->back[k]) || !light(b->sun_front[k]) ||
          !light(b->sun_back[k]))
        std::abort();
    for (const penumbra::Rgb& c : b->radiance)
      if (!light(c)) std::abort();
  }
  std::remove(path.c_str());
  return 0;
}
