// `penumbra bake SCENE -o ATLAS.exr`: the surface radiance cascades' light baked into an atlas
// file, which `penumbra render SCENE --method surface --atlas ATLAS.exr` views from any camera.
#pragma once

#include <memory>
#include <string>

#include "penumbra/spaceland/render.hpp"

namespace CLI {
class App;
}

struct BakeArgs {
  std::string scene, output;
  penumbra::spaceland::SurfaceOptions surface;
  int bounces = 1;
  int threads = 0;
  std::string max_memory = "8G";
  bool no_radiance = false;
  bool json = false;
  bool quiet = false;
};

struct BakeCommand {
  CLI::App* app = nullptr;
  BakeArgs args;
  bool parsed() const;
};

// Registers the subcommand on `app`; its options write into the returned command's args.
std::unique_ptr<BakeCommand> add_bake_command(CLI::App& app);

// Exit code: 0 success, 1 bad input or failure, 2 usage error.
int run_bake(const BakeArgs& args);
