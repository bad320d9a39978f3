// `penumbra paint`: the interactive light painter (a GLFW window, OpenGL and Dear ImGui).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "penumbra/flatland/render.hpp"
#include "render_options.hpp"

namespace CLI {
class App;
class Option;
}  // namespace CLI

struct PaintArgs {
  PaintArgs() {
    options.method = penumbra::flatland::Method::hrc;  // the fastest CPU method
    options.pt.spp = 4;                                // a quick look, not a reference
  }
  penumbra::flatland::RenderOptions options;  // the panel's starting settings (method, device, ...)
  RenderOptionFlags flags;                    // applied to `options` by run_paint
  std::string scene;                          // empty: a blank canvas of `size`
  std::string size = "256x256";               // cells, for a blank canvas
  const CLI::Option* size_option = nullptr;   // --size, to refuse it beside a scene file
  std::string replay;                         // stroke file to paint at start
  std::string screenshot;                     // PNG of the window after the replay; then exit
  std::string record;                         // stroke file written at exit
  std::string save;                           // scene file (JSON + PNG layers) written at exit
  float zoom = 0;                             // window pixels per cell (0: fit about 800 pixels)
  float emission_scale = 64;
  bool emission_scale_given = false;  // else a loaded painting keeps its own scale
  std::optional<float> exposure;      // empty: each frame is exposed from its picture
  int frames = 0;                     // > 0: solve continuously, exit after this many solver frames
  bool stats = false;
  bool plain = false;  // no material overlay: the window shows what `penumbra render` writes
};

struct PaintCommand {
  CLI::App* app = nullptr;
  PaintArgs args;
  bool parsed() const;
};

std::unique_ptr<PaintCommand> add_paint_command(CLI::App& app);

// Exit code: 0 success, 1 bad input, no display or failure, 2 usage error.
int run_paint(const PaintArgs& args);
