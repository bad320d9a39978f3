// `penumbra view`: fly through a 3D scene lit by a radiance-cascade method (a GLFW window,
// OpenGL and Dear ImGui). docs/VIEWER.md.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "penumbra/spaceland/render.hpp"

namespace CLI {
class App;
}  // namespace CLI

struct ViewArgs {
  std::string scene;
  std::string method = "ssrc";
  std::string size;        // the view, WxH pixels (empty: the scene camera's, within 1024x768)
  float scale = 0;         // internal resolution over the view's (0: from --target-ms)
  float target_ms = 33;    // the frame time the automatic internal resolution aims at
  bool still_full = true;  // a still camera gets a frame at the view's full resolution
  std::string upscale =
      "guided";  // or bilinear: how a frame below the view's size is brought to it
  int bounces = 1;
  int temporal = 0;    // ssrc's and spwi's temporal accumulation: the history's frames (0: off)
  int grid_slabs = 0;  // the grid's solve spread over frames, slabs a frame (0: off)
  int threads = 0;
  std::string max_memory = "8G";
  std::optional<float> exposure;  // empty: automatic
  std::string atlas;              // surface: view from this baked atlas
  std::string replay;             // camera and panel events to play
  std::string record;             // the session's events, written at exit
  std::string screenshot;         // PNG of the window once the last view is shown; then exit
  std::string save;               // "Save view" at exit: the scene file with this camera
  int frames = 0;                 // > 0: render continuously, exit after this many frames
  bool stats = false;
};

struct ViewCommand {
  CLI::App* app = nullptr;
  ViewArgs args;
  bool parsed() const;
};

std::unique_ptr<ViewCommand> add_view_command(CLI::App& app);

// Exit code: 0 success, 1 bad input, no display or failure, 2 usage error, 130 interrupted.
int run_view(const ViewArgs& args);
