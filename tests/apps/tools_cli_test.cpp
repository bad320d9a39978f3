// The programs shipped besides `penumbra` (the tools and the benchmarks' own front ends) behave
// like commands: --help and --version exit 0 and do no work, a usage error exits 2, an output
// folder that cannot be made exits 1 before the work and leaves nothing behind.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "penumbra/spaceland/scene.hpp"
#include "penumbra/version.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using penumbra::testing::CliResult;

struct Tool {
  const char* name;
  const char* path;
};

// The benchmarks' front ends where bench/ is built (not in the sanitizer build).
const std::vector<Tool> kTools = {
    {"penumbra_make_scenes", PENUMBRA_MAKE_SCENES},
    {"penumbra_scene_family", PENUMBRA_SCENE_FAMILY},
#ifdef PENUMBRA_QUALITY
    {"penumbra_quality", PENUMBRA_QUALITY},
    {"penumbra_quality3d", PENUMBRA_QUALITY3D},
    {"penumbra_gpu_passes", PENUMBRA_GPU_PASSES},
    {"penumbra_grid_scaling", PENUMBRA_GRID_SCALING},
    {"penumbra_quality_walls", PENUMBRA_QUALITY_WALLS},
    {"penumbra_temporal", PENUMBRA_TEMPORAL},
#endif
};

class ToolsCli : public ::testing::Test {
 protected:
  CliResult run(const char* tool, const std::vector<std::string>& args) const {
    return penumbra::testing::run_program(tool, args, tmp_.root(), true);
  }
  // What the tool left in its working folder, besides the captured output.
  std::vector<std::string> left() const {
    std::vector<std::string> names = tmp_.entries();
    std::erase_if(names,
                  [](const std::string& n) { return n == "stdout.txt" || n == "stderr.txt"; });
    return names;
  }
  penumbra::testing::TestDir tmp_{"tools"};
};

TEST_F(ToolsCli, HelpAndVersionExitZeroAndDoNothing) {
  for (const Tool& t : kTools) {
    const CliResult help = run(t.path, {"--help"});
    EXPECT_EQ(help.status, 0) << t.name << "\n" << help.err;
    EXPECT_NE(help.out.find("Usage:"), std::string::npos) << t.name << "\n" << help.out;
    EXPECT_NE(help.out.find("--version"), std::string::npos) << t.name;
    EXPECT_TRUE(left().empty()) << t.name << " left " << left().front();
    const CliResult version = run(t.path, {"--version"});
    EXPECT_EQ(version.status, 0) << t.name;
    EXPECT_NE(version.out.find(std::string(t.name) + " (penumbra " + penumbra::kVersion + ")"),
              std::string::npos)
        << t.name << ": " << version.out;
  }
}

TEST_F(ToolsCli, UsageErrorsExitTwo) {
  for (const Tool& t : kTools) {
    const CliResult r = run(t.path, {"--no-such-option", "folder"});
    EXPECT_EQ(r.status, 2) << t.name << "\n" << r.err;
    EXPECT_NE(r.err.find("--no-such-option"), std::string::npos) << t.name << "\n" << r.err;
    EXPECT_TRUE(left().empty()) << t.name;
  }
  // The folder is required where there is no sensible default.
  const CliResult r = run(PENUMBRA_MAKE_SCENES, {});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("folder"), std::string::npos) << r.err;
#ifdef PENUMBRA_QUALITY
  EXPECT_EQ(run(PENUMBRA_QUALITY3D, {}).status, 2);
  EXPECT_EQ(run(PENUMBRA_TEMPORAL, {}).status, 2);  // the scene is required
  const CliResult missing = run(PENUMBRA_TEMPORAL, {"no-such-scene.json"});
  EXPECT_EQ(missing.status, 1) << missing.err;
  EXPECT_NE(missing.err.find("no-such-scene.json"), std::string::npos) << missing.err;
  const CliResult method = run(PENUMBRA_TEMPORAL, {"x.json", "--method", "pt"});
  EXPECT_EQ(method.status, 2) << method.err;  // ssrc, spwi or grid only
  // A malformed value.
  const CliResult runs = run(PENUMBRA_GPU_PASSES, {"--runs", "many"});
  EXPECT_EQ(runs.status, 2) << runs.err;
#endif
}

#ifdef PENUMBRA_BENCH
// The benchmarks take Google Benchmark's flags (its --help), and our --version and exit codes.
TEST_F(ToolsCli, BenchmarksTakeVersionAndRefuseUnknownFlags) {
  const CliResult version = run(PENUMBRA_BENCH, {"--version"});
  EXPECT_EQ(version.status, 0);
  EXPECT_NE(version.out.find(std::string("penumbra_bench (penumbra ") + penumbra::kVersion),
            std::string::npos)
      << version.out;
  const CliResult bad = run(PENUMBRA_BENCH, {"--benchmark_filer=Hrc"});
  EXPECT_EQ(bad.status, 2) << bad.err;
  EXPECT_NE(bad.err.find("--benchmark_filer"), std::string::npos) << bad.err;
  const CliResult list =
      run(PENUMBRA_BENCH, {"--benchmark_list_tests", "--benchmark_filter=HrcGrid"});
  EXPECT_EQ(list.status, 0) << list.err;
  EXPECT_NE(list.out.find("BM_HrcGrid/512"), std::string::npos) << list.out;
}
#endif

TEST_F(ToolsCli, AFolderThatCannotBeMadeExitsOneBeforeTheWork) {
  const std::string bad = (tmp_.root() / "missing" / "deeper").string();
  std::vector<const char*> tools = {PENUMBRA_MAKE_SCENES, PENUMBRA_SCENE_FAMILY};
#ifdef PENUMBRA_QUALITY
  tools.push_back(PENUMBRA_QUALITY);
#endif
  for (const char* tool : tools) {
    const CliResult r = run(tool, {bad});
    EXPECT_EQ(r.status, 1) << tool << "\n" << r.err;
    EXPECT_NE(r.err.find("missing"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(tmp_.root() / "missing")) << tool << " made folders";
    EXPECT_TRUE(r.out.empty()) << tool << " printed " << r.out;
  }
  // A file where the folder should be.
  const std::string file = tmp_.write("taken", "x");
  const CliResult r = run(PENUMBRA_MAKE_SCENES, {file});
  EXPECT_EQ(r.status, 1) << r.err;
}

// The scene family: each class's scenes load as 3D scenes (their meshes from Debian's packages
// found), and a seed writes the same bytes again, another seed other scenes.
TEST_F(ToolsCli, SceneFamilyWritesLoadableScenesTheSameForASeed) {
  ASSERT_EQ(run(PENUMBRA_SCENE_FAMILY, {"a", "--count", "2"}).status, 0);
  ASSERT_EQ(run(PENUMBRA_SCENE_FAMILY, {"b", "--count", "2"}).status, 0);
  ASSERT_EQ(run(PENUMBRA_SCENE_FAMILY, {"c", "--count", "2", "--seed", "7"}).status, 0);
  for (const char* cls : {"night", "behind", "window"})
    for (int k = 0; k < 2; ++k) {
      const std::string name = std::string(cls) + "_" + std::to_string(k) + ".json";
      const fs::path a = tmp_.root() / "a" / name;
      const penumbra::Expected<penumbra::spaceland::Scene> scene =
          penumbra::spaceland::load_scene(a.string());
      ASSERT_TRUE(scene.ok()) << name << ": " << scene.error().message;
      EXPECT_FALSE(scene->meshes.empty() && scene->spheres.empty()) << name;
      EXPECT_EQ(penumbra::testing::slurp(a), penumbra::testing::slurp(tmp_.root() / "b" / name));
      EXPECT_NE(penumbra::testing::slurp(a), penumbra::testing::slurp(tmp_.root() / "c" / name));
    }
}

TEST_F(ToolsCli, MakeScenesMakesOneMissingFolder) {
  const CliResult r = run(PENUMBRA_MAKE_SCENES, {"made/"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(tmp_.root() / "made" / "lights_2.json"));
  EXPECT_TRUE(fs::is_directory(tmp_.root() / "made" / "layers"));
}

}  // namespace
