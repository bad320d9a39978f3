// penumbra: the command line. A thin front end over libpenumbra; each subcommand lives in its
// own file (render_cmd, compare_cmd, quality_cmd, paint_cmd, bake_cmd,
// field_cmd, view_cmd).
// Exit codes: 0 success, 1 bad input or runtime failure, 2 usage error.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "bake_cmd.hpp"
#include "compare_cmd.hpp"
#include "field_cmd.hpp"
#include "paint_cmd.hpp"
#include "penumbra/penumbra.hpp"
#include "quality_cmd.hpp"
#include "render_cmd.hpp"
#include "view_cmd.hpp"

namespace {
constexpr int kUsage = 2;

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// The name closest to `word` within 2 edits (1 for words of 4 letters or fewer), or "".
std::string closest(const std::string& word, const std::vector<std::string>& names) {
  std::string best;
  std::size_t best_d = word.size() <= 4 ? 2 : 3;
  for (const std::string& n : names)
    if (const std::size_t d = edit_distance(word, n); d < best_d) best = n, best_d = d;
  return best;
}

// After a usage error: "did you mean" for a mistyped subcommand or option of the subcommand.
void suggest(const CLI::App& app, int argc, char** argv) {
  const std::vector<const CLI::App*> subs =
      app.get_subcommands([](const CLI::App*) { return true; });
  std::vector<std::string> commands;
  for (const CLI::App* s : subs) commands.push_back(s->get_name());
  const CLI::App* sub = nullptr;
  int i = 1;
  for (; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.starts_with("-")) continue;
    for (const CLI::App* s : subs)
      if (s->get_name() == word) sub = s;
    if (!sub) {
      if (const std::string c = closest(word, commands); !c.empty())
        std::cerr << "Did you mean 'penumbra " << c << "'?\n";
      return;
    }
    break;
  }
  if (!sub) return;
  std::vector<std::string> names;
  for (const CLI::Option* opt : sub->get_options())
    for (const std::string& n : opt->get_lnames()) names.push_back("--" + n);
  for (++i; i < argc; ++i) {
    std::string word = argv[i];
    if (!word.starts_with("--")) continue;
    word = word.substr(0, word.find('='));
    if (std::find(names.begin(), names.end(), word) != names.end()) continue;
    if (const std::string c = closest(word, names); !c.empty())
      std::cerr << "Did you mean " << c << " (for " << word << ")?\n";
  }
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Penumbra: global illumination with radiance cascades."};
  app.set_version_flag("--version", std::string("penumbra ") + penumbra::kVersion);
  app.require_subcommand(1);

  const std::unique_ptr<RenderCommand> render = add_render_command(app);
  const std::unique_ptr<CompareCommand> compare = add_compare_command(app);
  const std::unique_ptr<QualityCommand> quality = add_quality_command(app);
  const std::unique_ptr<PaintCommand> paint = add_paint_command(app);
  const std::unique_ptr<BakeCommand> bake = add_bake_command(app);
  const std::unique_ptr<FieldCommand> field = add_field_command(app);
  const std::unique_ptr<ViewCommand> view = add_view_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --version
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    suggest(app, argc, argv);
    return kUsage;
  }
  if (render->parsed()) return run_render(render->args);
  if (compare->parsed()) return run_compare(compare->args);
  if (quality->parsed()) return run_quality(quality->args);
  if (paint->parsed()) return run_paint(paint->args);
  if (bake->parsed()) return run_bake(bake->args);
  if (field->parsed()) return run_field(field->args);
  if (view->parsed()) return run_view(view->args);
  return kUsage;
}
