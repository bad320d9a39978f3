// The scenes shipped under scenes/ load, validate and build.
#include <gtest/gtest.h>

#include <filesystem>

#include "penumbra/scene.hpp"

namespace penumbra {
namespace {

TEST(ExampleScenes, AllLoadAndBuild) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(PENUMBRA_SOURCE_DIR "/scenes")) {
    if (entry.path().extension() != ".json") continue;
    ++count;
    Expected<SceneDesc> d = load_scene(entry.path().string());
    ASSERT_TRUE(d.ok()) << d.error().message;
    Expected<Scene> s = build_scene(*d);
    ASSERT_TRUE(s.ok()) << s.error().message;
    float emitted = 0;
    for (float e : s->emission) emitted += e;
    EXPECT_GT(emitted, 0.0f) << entry.path() << " has no light";
  }
  EXPECT_GE(count, 2);
}

}  // namespace
}  // namespace penumbra
