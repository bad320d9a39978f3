// The 3D example scenes under scenes/3d/: each has a description and some light, and each is in
// scenes/README.md with its command and its picture.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "test_support.hpp"

namespace penumbra::spaceland {
namespace {

namespace fs = std::filesystem;
const fs::path kScenes = fs::path(PENUMBRA_SOURCE_DIR) / "scenes";

std::vector<std::string> scene_names() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(kScenes / "3d"))
    if (e.path().extension() == ".json") names.push_back(e.path().stem().string());
  return names;
}

TEST(ExampleScenes3d, EachHasADescriptionAndLight) {
  const std::vector<std::string> names = scene_names();
  ASSERT_GE(names.size(), 10u);
  for (const std::string& name : names) {
    const fs::path file = kScenes / "3d" / (name + ".json");
    const nlohmann::json j = nlohmann::json::parse(penumbra::testing::slurp(file));
    ASSERT_TRUE(j.contains("description") && j["description"].is_string()) << name;
    EXPECT_GE(j["description"].get<std::string>().size(), 20u) << name;
    Expected<Scene> s = load_scene(file.string());
    ASSERT_TRUE(s.ok()) << s.error().message;
    bool lit = s->has_sun;
    const Rgb sky[3] = {s->sky.zenith, s->sky.horizon, s->sky.ground};
    for (const Rgb& c : sky) lit = lit || c.r > 0 || c.g > 0 || c.b > 0;
    for (const Material& m : s->materials)
      lit = lit || m.emission.r > 0 || m.emission.g > 0 || m.emission.b > 0;
    EXPECT_TRUE(lit) << name << " has no light";
  }
}

TEST(ExampleScenes3d, EachIsInTheReadmeWithItsPicture) {
  const std::string readme = penumbra::testing::slurp(kScenes / "README.md");
  ASSERT_FALSE(readme.empty());
  for (const std::string& name : scene_names()) {
    EXPECT_NE(readme.find("scenes/3d/" + name + ".json"), std::string::npos) << name;
    const std::string picture = "images/3d/" + name + ".png";
    EXPECT_NE(readme.find("](" + picture + ")"), std::string::npos) << name << ": no " << picture;
    EXPECT_TRUE(fs::is_regular_file(kScenes / picture)) << picture;
  }
}

// Issue 39's "bake and --atlas work on every example scene": each one without fog bakes to a
// file and is seen from it (32x24, a coarse atlas; AtlasFile.* checks that a view from the file
// is a bake-and-view's), with light in the picture; each one with fog is refused by name, writing
// nothing. The meshes with and without lightmap UVs (the glTF box, the engine, the bunny) are among
// them.
TEST(ExampleScenes3d, EachBakesToAFileAndIsSeenFromIt) {
  penumbra::testing::TestDir dir("examples3d");
  for (const std::string& name : scene_names()) {
    Expected<Scene> s = load_scene((kScenes / "3d" / (name + ".json")).string());
    ASSERT_TRUE(s.ok()) << s.error().message;
    s->camera.width = 32;
    s->camera.height = 24;
    RenderOptions o;
    o.method = Method::surface;
    o.surface.texels = 4096;
    o.surface.directions = 16;
    const std::string file = dir.file(name + ".exr");
    const Expected<BakeResult> baked = bake(*s, o, file, false);
    if (!s->media.empty()) {
      ASSERT_FALSE(baked) << name;
      EXPECT_NE(baked.error().message.find("surface cannot carry fog"), std::string::npos)
          << baked.error().message;
      EXPECT_FALSE(fs::exists(file)) << name;
      continue;
    }
    ASSERT_TRUE(baked) << name << ": " << baked.error().message;
    EXPECT_GT(baked->covered, 2000u) << name;
    o.surface.atlas = file;
    const Expected<RenderResult> seen = render(*s, o);
    ASSERT_TRUE(seen) << name << ": " << seen.error().message;
    const ImageRgb& b = seen->radiance;
    double sum = 0;
    for (std::size_t i = 0; i < b.size(); ++i) sum += b.data()[i];
    EXPECT_GT(sum, 0) << name << ": a black picture";
  }
}

// The 3D document example of docs/scene-format.md parses as written (its mesh is the bunny
// Debian installs) and renders: a user can copy it.
TEST(ExampleScenes3d, TheFormatDocumentsExampleRenders) {
  const std::string doc =
      penumbra::testing::slurp(fs::path(PENUMBRA_SOURCE_DIR) / "docs/scene-format.md");
  std::string text;
  for (std::size_t at = doc.find("```json\n"); at != std::string::npos && text.empty();
       at = doc.find("```json\n", at + 1)) {
    const std::size_t end = doc.find("```", at + 8);
    ASSERT_NE(end, std::string::npos);
    const std::string block = doc.substr(at + 8, end - at - 8);
    if (block.find("\"dimensions\": 3") != std::string::npos) text = block;
  }
  ASSERT_FALSE(text.empty()) << "no 3D example in docs/scene-format.md";
  Expected<Scene> s = parse_scene(text, (kScenes / "3d" / "example.json").string());
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_GE(s->objects.size(), 5u);
  RenderOptions o;
  o.pt.spp = 1;
  s->camera.width = 16;
  s->camera.height = 12;
  Expected<RenderResult> r = render(*s, o);
  ASSERT_TRUE(r.ok()) << r.error().message;
  double sum = 0;
  for (std::size_t i = 0; i < r->radiance.size(); ++i) sum += r->radiance.data()[i];
  EXPECT_GT(sum, 0.0);
}

}  // namespace
}  // namespace penumbra::spaceland
