// `penumbra render`: one scene, one method, images out.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "penumbra/flatland/render.hpp"
#include "render_options.hpp"

namespace CLI {
class App;
}

struct RenderArgs {
  std::string scene;  // empty: the built-in scene
  std::vector<std::string> outputs;
  std::string max_memory = "8G";
  float exposure = 0;
  bool json = false;
  bool quiet = false;
  penumbra::flatland::RenderOptions options;
  RenderOptionFlags flags;  // applied to `options` by run_render
};

struct RenderCommand {
  CLI::App* app = nullptr;
  RenderArgs args;
  bool parsed() const;
};

// Registers the subcommand on `app`; its options write into the returned command's args.
std::unique_ptr<RenderCommand> add_render_command(CLI::App& app);

// Exit code: 0 success, 1 bad input or failure, 2 usage error, 130 interrupted (the image of the
// samples so far is still written).
int run_render(const RenderArgs& args);
