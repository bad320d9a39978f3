// `penumbra bench-quality`: every method against a converged path-traced reference, as error
// against time (a CSV, a log-log plot, a markdown table).
#pragma once

#include <memory>
#include <string>

namespace CLI {
class App;
}

struct QualityArgs {
  std::string scene;
  std::string out = "out/quality";
  std::string cache;  // empty: <out>/cache
  std::string doc;    // a markdown file whose bench-quality section receives the table
  int bounces = 1;
  int reference_spp = 1024;
  int max_spp = 256;
  int threads = 0;
  bool quick = false;
};

struct QualityCommand {
  CLI::App* app = nullptr;
  QualityArgs args;
  bool parsed() const;
};

// Registers the subcommand on `app`; its options write into the returned command's args.
std::unique_ptr<QualityCommand> add_quality_command(CLI::App& app);

// Exit code: 0 success, 1 bad input or failure, 2 usage error.
int run_quality(const QualityArgs& args);
