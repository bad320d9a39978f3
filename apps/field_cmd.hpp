// `penumbra field SCENE --window ... -o VIEW`: the direct radiance field renderer (seed 001
// section 4.4): what lies behind a window path-traced into its surface radiance cascades once,
// then seen from the scene's camera and cameras moved around the window, each view compared with
// the path tracer where asked.
#pragma once

#include <memory>
#include <string>

#include "penumbra/spaceland/field.hpp"

namespace CLI {
class App;
}

struct FieldArgs {
  std::string scene, output, window;
  int width = 0, height = 0;  // > 0: the views' size instead of the scene camera's
  penumbra::spaceland::FieldOptions field;
  int views = 1;
  int reference = 0;  // path-traced samples a pixel of each view's truth; 0: none
  std::string max_memory = "8G";
  bool json = false;
  bool quiet = false;
};

struct FieldCommand {
  CLI::App* app = nullptr;
  FieldArgs args;
  bool parsed() const;
};

// Registers the subcommand on `app`; its options write into the returned command's args.
std::unique_ptr<FieldCommand> add_field_command(CLI::App& app);

// Exit code: 0 success, 1 bad input or failure, 2 usage error.
int run_field(const FieldArgs& args);
