// penumbra: the command line. A thin front end over libpenumbra; each subcommand lives in its
// own file (render_cmd, compare_cmd, quality_cmd, paint_cmd).
// Exit codes: 0 success, 1 bad input or runtime failure, 2 usage error.
#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "compare_cmd.hpp"
#include "paint_cmd.hpp"
#include "penumbra/penumbra.hpp"
#include "quality_cmd.hpp"
#include "render_cmd.hpp"

namespace {
constexpr int kUsage = 2;
}

int main(int argc, char** argv) {
  CLI::App app{"Penumbra: global illumination with radiance cascades."};
  app.set_version_flag("--version", std::string("penumbra ") + penumbra::kVersion);
  app.require_subcommand(1);

  const std::unique_ptr<RenderCommand> render = add_render_command(app);
  const std::unique_ptr<CompareCommand> compare = add_compare_command(app);
  const std::unique_ptr<QualityCommand> quality = add_quality_command(app);
  const std::unique_ptr<PaintCommand> paint = add_paint_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --version
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kUsage;
  }
  if (render->parsed()) return run_render(render->args);
  if (compare->parsed()) return run_compare(compare->args);
  if (quality->parsed()) return run_quality(quality->args);
  if (paint->parsed()) return run_paint(paint->args);
  return kUsage;
}
