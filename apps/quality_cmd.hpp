// `penumbra bench-quality`: every method against a converged path-traced reference, as error
// against time (a CSV, a log-log plot, a markdown table).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "analysis/study.hpp"
#include "penumbra/progress.hpp"

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

// A 3D scene's study (quality3d_cmd.cpp): the path tracer's curve and SPWI's variants.
int run_quality3d(const QualityArgs& args);

// What the 2D and 3D studies share: the output folder, the cached references' folder, and the
// document whose section receives the table.
namespace quality_detail {

struct Montage {
  std::string file;     // under the output folder
  std::string caption;  // in the document, after the scene's name
  penumbra::ImageRgb8 picture;
};

// The reference's progress on a terminal (none otherwise, so that logs stay clean).
std::function<void(const penumbra::RenderProgress&)> reference_progress();

struct StudyOutput {
  explicit StudyOutput(const QualityArgs& a) : args(a) {}
  const QualityArgs& args;
  std::string section;  // `prefix`, the scene file's name without .json, `suffix`
  std::string cache;    // the cached references' folder

  // Checks the document has the section's markers and creates the folders. 3D scenes' sections
  // have the prefix "3d/", so that scenes/cornell.json and scenes/3d/cornell.json differ.
  penumbra::Status prepare(const std::string& prefix = "", const std::string& suffix = "");
  // Equal-error times and the reference's own error into `rows` and `ref`; writes the CSV, the
  // table, the plot and `montages`, then the document's section. Returns the exit code.
  int finish(std::vector<penumbra::study::Row>& rows, penumbra::study::Reference& ref,
             const std::vector<Montage>& montages) const;

 private:
  penumbra::Expected<std::string> spliced_doc(const std::string& body) const;
};

}  // namespace quality_detail
