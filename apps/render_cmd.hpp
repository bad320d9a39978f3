// `penumbra render`: one scene, one method, images out.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/flatland/render.hpp"
#include "penumbra/spaceland/render.hpp"
#include "render_options.hpp"

namespace CLI {
class App;
}

struct RenderArgs {
  std::string scene;   // empty: the built-in scene
  std::string method;  // empty: the world's default (rc in 2D, pt in 3D)
  // 3D only: the camera's image size (0: the scene's) and what the image holds.
  int width = 0, height = 0;
  std::string aov = "radiance";
  // 3D spwi: its own options (--probe-spacing, --directions, --interval and --cascades are
  // shared with 2D's cascades and copied when given).
  penumbra::spaceland::SpwiOptions spwi;
  std::string merge = "bilinear3d", sun = "direct";
  bool disjoint = false;  // --disjoint: spwi's thesis intervals (SpwiOptions::overlap off)
  std::vector<std::string> outputs;
  std::string max_memory = "8G";
  float exposure = 0;
  bool json = false;
  bool quiet = false;
  penumbra::flatland::RenderOptions options;
  RenderOptionFlags flags;        // applied to `options` by run_render
  const CLI::App* app = nullptr;  // the subcommand, to tell which options were given
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

// What both worlds check before loading a scene: output types and writability, --max-memory
// (parsed into `max_memory`) and --exposure. Prints the message; returns 0 or the exit code.
int check_render_args(const RenderArgs& args, std::uint64_t& max_memory);

// The 3D half of `render` (render3d_cmd.cpp): `args.scene` is a 3D document.
int render_scene_3d(const RenderArgs& args);
