// `penumbra compare`: error metrics of one linear image against another, with pictures.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace CLI {
class App;
}

struct CompareArgs {
  std::string test, reference, scene;
  std::string heatmap, montage;   // empty: not written
  std::optional<float> exposure;  // EV of the montage's test and reference panels; empty:
                                  // chosen from the reference, as render's PNGs are
  double heatmap_scale = 0;       // the error colours' +-S (0: the 99th percentile of |error|)
  std::vector<int> crop;          // empty, or X Y W H: compare only this rectangle of cells
  bool json = false;
  bool quiet = false;
  bool radiance = false;          // 3D images: pixels of radiance (set too by a 3D --scene)
  std::string max_memory = "8G";  // each image may take half of it to read
};

struct CompareCommand {
  CLI::App* app = nullptr;
  CompareArgs args;
  bool parsed() const;
};

// Registers the subcommand on `app`; its options write into the returned command's args.
std::unique_ptr<CompareCommand> add_compare_command(CLI::App& app);

// Exit code: 0 success, 1 bad input or failure, 2 usage error.
int run_compare(const CompareArgs& args);
