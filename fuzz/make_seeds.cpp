// Writes the fuzzers' generated seeds, so no binary seed lives in git (scripts/fuzz.sh):
//   penumbra_fuzz_seeds <dir>
// <dir>/image: tiny PFM, EXR (one per compression) and PNG (8- and 16-bit) files;
// <dir>/layers: 8x8 layer images and <dir>/scene: a scene that names them, for fuzz_scene;
// <dir>/atlas: atlases baked for atlas_scene.hpp's scene, for fuzz_atlas.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <vector>

#include "atlas_scene.hpp"
#include "io/image_io.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/spaceland/render.hpp"

namespace {

namespace fs = std::filesystem;
using penumbra::ImageRgb;
using penumbra::Status;

constexpr int kSide = 8;

ImageRgb gradient() {
  ImageRgb img(kSide, kSide);
  for (int y = 0; y < kSide; ++y)
    for (int x = 0; x < kSide; ++x) img.set(x, y, {x / 7.0f, y / 7.0f, 0.5f});
  return img;
}

bool ok(const Status& s) {
  if (!s) std::fprintf(stderr, "penumbra_fuzz_seeds: %s\n", s.error().message.c_str());
  return s.ok();
}

// An EXR of float R, G, B (or Y alone) with the given compression.
void write_exr(const fs::path& path, Imf::Compression compression, bool grey) {
  const ImageRgb img = gradient();
  Imf::Header header(kSide, kSide);
  header.compression() = compression;
  const char* names[3] = {"R", "G", "B"};
  const int channels = grey ? 1 : 3;
  for (int c = 0; c < channels; ++c)
    header.channels().insert(grey ? "Y" : names[c], Imf::Channel(Imf::FLOAT));
  Imf::OutputFile file(path.c_str(), header);
  Imf::FrameBuffer fb;
  for (int c = 0; c < channels; ++c) {
    fb.insert(grey ? "Y" : names[c], Imf::Slice(Imf::FLOAT, (char*)(img.data() + c),
                                                sizeof(float) * 3, sizeof(float) * 3 * kSide));
  }
  file.setFrameBuffer(fb);
  file.writePixels(kSide);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <dir>\n", argv[0]);
    return 2;
  }
  const fs::path dir = argv[1];
  for (const char* sub : {"image", "layers", "scene"}) fs::create_directories(dir / sub);
  const fs::path image = dir / "image";
  const ImageRgb img = gradient();
  bool good = ok(penumbra::io::write_pfm((image / "rgb.pfm").string(), img));
  // A one-channel PFM, written by hand: header, then little-endian floats (scale -1).
  {
    std::ofstream grey(image / "grey.pfm", std::ios::binary);
    grey << "Pf\n2 2\n-1.0\n";
    const float v[4] = {0, 0.25f, 0.5f, 1};
    grey.write(reinterpret_cast<const char*>(v), sizeof v);
  }
  try {
    const Imf::Compression kinds[] = {
        Imf::NO_COMPRESSION,  Imf::RLE_COMPRESSION,   Imf::ZIPS_COMPRESSION, Imf::ZIP_COMPRESSION,
        Imf::PIZ_COMPRESSION, Imf::PXR24_COMPRESSION, Imf::B44_COMPRESSION,  Imf::DWAA_COMPRESSION};
    int k = 0;
    for (Imf::Compression c : kinds)
      write_exr(image / ("c" + std::to_string(k++) + ".exr"), c, false);
    write_exr(image / "grey.exr", Imf::ZIP_COMPRESSION, true);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "penumbra_fuzz_seeds: EXR: %s\n", e.what());
    good = false;
  }
  std::vector<unsigned char> rgb8(kSide * kSide * 3);
  for (std::size_t i = 0; i < rgb8.size(); ++i) rgb8[i] = static_cast<unsigned char>(i * 5);
  good = good && ok(penumbra::io::write_png8((image / "rgb8.png").string(), kSide, kSide, rgb8));
  std::vector<std::uint16_t> grey16(kSide * kSide), rgb16(kSide * kSide * 3);
  for (std::size_t i = 0; i < grey16.size(); ++i) grey16[i] = static_cast<std::uint16_t>(i * 1000);
  for (std::size_t i = 0; i < rgb16.size(); ++i) rgb16[i] = static_cast<std::uint16_t>(i * 300);
  for (const auto& [name, channels, codes] :
       {std::tuple{"grey16.png", 1, &grey16}, std::tuple{"rgb16.png", 3, &rgb16}}) {
    auto staged =
        penumbra::io::stage_png16((image / name).string(), kSide, kSide, channels, *codes);
    good = good && ok(staged ? penumbra::io::publish(*staged) : Status(staged.error()));
    if (good)
      fs::copy_file(image / name, dir / "layers" / name, fs::copy_options::overwrite_existing);
  }
  good = good && ok(penumbra::io::write_pfm((dir / "layers" / "rgb.pfm").string(), img));

  // A scene naming the layers as scripts/fuzz.sh lays them out (relative to the fuzzer's
  // working directory), with one shape of each kind.
  using namespace penumbra::flatland;
  SceneDesc d;
  d.width = d.height = kSide;
  d.environment = {0.01f, 0.01f, 0.02f};
  d.shapes.push_back({Circle{{2, 2}, 1.5f}, Material{{4, 3, 1}, 1, {}}});
  d.shapes.push_back({Box{{5, 5}, {3, 1}, 30}, Material{{}, 1, {0.5f, 0.5f, 0.5f}}});
  d.shapes.push_back({Segment{{1, 7}, {7, 6}, 0.5f}, Material{{}, 0.3f, {0.2f, 0.8f, 0.2f}}});
  d.shapes.push_back({Polygon{{{6, 1}, {7.5f, 2}, {6.5f, 3.5f}}}, Material{{1, 0, 0}, 1, {}}});
  const std::string text =
      scene_json(d, {"layers/rgb16.png", "layers/grey16.png", "layers/rgb.pfm", 2}, "fuzz seed");
  std::ofstream(dir / "scene" / "layers.json") << text;

  // Two small atlases (the fuzzer's inputs stop at 16 KiB): 64 texels, Q0 4.
  fs::create_directories(dir / "atlas");
  namespace sl = penumbra::spaceland;
  sl::RenderOptions o;
  o.method = sl::Method::surface;
  o.surface.texels = 64;
  o.surface.directions = 4;
  for (const bool radiance : {false, true}) {
    const auto baked =
        sl::bake(atlas_fuzz_scene(), o,
                 (dir / "atlas" / (radiance ? "radiance.exr" : "plain.exr")).string(), radiance);
    good = good && ok(baked ? Status() : Status(baked.error()));
  }
  return good ? 0 : 1;
}
