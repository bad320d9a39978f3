// `penumbra paint`: draw lights, walls and fog with a brush and watch the global illumination.
// This file checks the options and the files; the window is paint/window.cpp.
#include "paint_cmd.hpp"

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "cli_enums.hpp"
#include "flatland/paint/canvas.hpp"
#include "io/path_util.hpp"
#include "paint/window.hpp"
#include "parse.hpp"
#include "penumbra/penumbra.hpp"
#include "render_options.hpp"

using namespace penumbra;
using namespace penumbra::flatland;

namespace {

constexpr int kUsage = 2;
constexpr int kFailure = 1;

}  // namespace

bool PaintCommand::parsed() const {
  return app->parsed();
}

std::unique_ptr<PaintCommand> add_paint_command(CLI::App& app) {
  auto cmd = std::make_unique<PaintCommand>();
  PaintArgs& a = cmd->args;
  cmd->app = app.add_subcommand("paint", "Paint lights, walls and fog; see the light at once");
  CLI::App* c = cmd->app;
  c->add_option("scene", a.scene, "Scene file to start from (JSON, format 1)")
      ->check(non_empty_path());
  a.size_option = c->add_option("--size", a.size,
                                "Grid of a blank canvas, WxH cells (a scene file has its own)")
                      ->capture_default_str();
  // The render options the window can change too, in two calls to keep the help in its order;
  // paint says its own help and allows fewer bounces.
  RenderOptionSet first, second;
  first.method = first.device = true;
  first.methods = {Method::hrc, Method::rc, Method::pt};
  first.method_help = "Method (switchable in the window)";
  first.device_help =
      "Where the solver runs: cpu, gpu (Vulkan: RC and HRC, every bounce and storage; the path "
      "tracer stays on the CPU), auto";
  second.storage = second.bounces = second.threads = true;
  second.max_bounces = 8;
  second.bounces_help = "Diffuse bounces";
  second.threads_help = "Solver threads (0: all cores)";
  add_render_options(c, a.options, a.flags, first);
  c->add_option("--replay", a.replay, "Stroke file to paint, one stroke per window frame");
  c->add_option("--screenshot", a.screenshot,
                "Save the window as PNG once the solver shows the final canvas, then exit");
  c->add_option("--record", a.record, "Write the strokes painted to this file at exit");
  c->add_option("--save", a.save,
                "Write the painting as a scene file (JSON + 16-bit PNG layers) at exit");
  c->add_option("--zoom", a.zoom, "Window pixels per cell (0: fit about 800 pixels)")
      ->check(real_range(0, 64))
      ->capture_default_str();
  c->add_option("--emission-scale", a.emission_scale,
                "Brightest radiance the canvas holds (the saved emission_scale); a scene's "
                "brightest cell raises it")
      ->check(real_range(1e-3, 1e9))
      ->each([&a](const std::string&) { a.emission_scale_given = true; })
      ->capture_default_str();
  add_render_options(c, a.options, a.flags, second);
  add_exposure_option(c, a.exposure,
                      "Display exposure in EV (default: automatic, from each frame's picture; "
                      "the panel shows it)");
  c->add_option("--frames", a.frames,
                "Solve continuously and exit after this many solver frames (measurement)")
      ->check(CLI::Range(0, 1 << 20));
  c->add_flag("--plain", a.plain,
              "Show the fluence exactly as `penumbra render` writes it (no dim floor for unlit "
              "walls and fog)");
  c->add_flag("--stats", a.stats, "At exit, print the median solve and window frame times");
  return cmd;
}

int run_paint(const PaintArgs& args) {
  PaintArgs a = args;  // the painter starts from the finished options
  finish_render_options(a.options, a.flags);
  // Everything the files say is checked before a window opens.
  Expected<paint::Canvas> canvas = Error{""};
  if (a.scene.empty()) {
    int w = 0, h = 0;
    if (!parse_grid_size(a.size, w, h)) {
      std::cerr << "penumbra paint: --size: expected WxH such as 256x256, found '" << a.size
                << "'\n";
      return kUsage;
    }
    canvas = paint::Canvas::blank(w, h, a.emission_scale);
  } else {
    if (a.size_option && a.size_option->count() > 0) {  // not silently ignored
      std::cerr << "penumbra paint: --size is for a blank canvas; " << a.scene
                << " has its own grid (resize it in the scene file)\n";
      return kUsage;
    }
    // The painter draws 2D scenes; a 3D one gets a message that says so.
    const Expected<int> dims = penumbra::spaceland::scene_dimensions(a.scene);
    if (!dims || *dims == 3) {
      std::cerr << "penumbra paint: "
                << (dims ? a.scene +
                               ": a 3D scene; the painter draws 2D scenes (render it with "
                               "`penumbra render`)"
                         : dims.error().message)
                << "\n";
      return kFailure;
    }
    Expected<SceneDesc> desc = load_scene(a.scene);
    canvas = desc ? paint::Canvas::from_scene(*desc, a.emission_scale_given ? a.emission_scale : 0)
                  : Expected<paint::Canvas>(desc.error());
  }
  if (!canvas) {
    std::cerr << "penumbra paint: " << canvas.error().message << "\n";
    return kFailure;
  }
  // Memory: the method's, plus the painter's copies of the canvas (the canvas, the stroke's
  // starting cells, the worker's two) and its undo steps.
  const RenderOptions& probe = a.options;
  if (Status s = check_options(canvas->width(), canvas->height(), probe); !s) {
    std::cerr << "penumbra paint: " << with_flags(s.error().message) << "\n";
    return kUsage;
  }
  const int w = canvas->width(), h = canvas->height();
  if (Status s = check_memory(w, h, probe, false); !s) {
    std::cerr << "penumbra paint: " << with_flags(s.error().message) << "\n";
    return kFailure;
  }
  if (Status s = painter::painter_memory(w, h, probe); !s) {
    std::cerr << "penumbra paint: " << s.error().message << "\n";
    return kFailure;
  }
  std::vector<paint::Stroke> strokes;
  if (!a.replay.empty()) {
    Expected<paint::StrokeFile> r = paint::load_strokes(a.replay);
    if (!r) {
      std::cerr << "penumbra paint: " << r.error().message << "\n";
      return kFailure;
    }
    for (std::size_t i = 0; i < r->strokes.size(); ++i)
      if (Status s =
              canvas->check(r->strokes[i].brush, a.replay + ": strokes[" + std::to_string(i) + "]");
          !s) {
        std::cerr << "penumbra paint: " << s.error().message << "\n";
        return kFailure;
      }
    if (r->width > 0 && (r->width != w || r->height != h))
      std::cerr << "penumbra paint: warning: " << a.replay << " was painted on a " << r->width
                << "x" << r->height << " grid; replaying it on " << w << "x" << h << "\n";
    strokes = std::move(r->strokes);
  }

  // Outputs: names checked, places writable, no two the same file.
  if (!a.screenshot.empty() && io::lowercase_extension(a.screenshot) != ".png") {
    std::cerr << "penumbra paint: --screenshot: " << a.screenshot << ": expected a .png name\n";
    return kUsage;
  }
  std::vector<std::pair<std::string, std::string>> outputs;  // option, path
  if (!a.screenshot.empty()) outputs.push_back({"--screenshot", a.screenshot});
  if (!a.save.empty()) {
    Expected<std::vector<std::string>> saved = paint::Canvas::save_paths(a.save);
    if (!saved) {
      std::cerr << "penumbra paint: --save: " << saved.error().message << "\n";
      return kUsage;
    }
    for (const std::string& p : *saved) outputs.push_back({"--save", p});
  }
  if (!a.record.empty()) outputs.push_back({"--record", a.record});
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    if (Status s = check_output(outputs[i].second); !s) {
      std::cerr << "penumbra paint: " << outputs[i].first << ": " << s.error().message << "\n";
      return kFailure;
    }
    auto canonical = [](const std::string& p) {
      std::error_code ec;
      std::filesystem::path c = std::filesystem::weakly_canonical(p, ec);
      if (ec) c = std::filesystem::absolute(p, ec).lexically_normal();
      return ec ? std::filesystem::path(p) : c;
    };
    const std::filesystem::path pi = canonical(outputs[i].second);
    for (std::size_t j = 0; j < i; ++j)
      if (pi == canonical(outputs[j].second)) {
        std::cerr << "penumbra paint: " << outputs[j].first << " and " << outputs[i].first
                  << " would both write " << outputs[i].second << "\n";
        return kUsage;
      }
  }
  try {
    painter::Painter p(a, std::move(*canvas), std::move(strokes));
    return p.run();
  } catch (const std::exception& e) {
    std::cerr << "penumbra paint: " << e.what() << "\n";
    return kFailure;
  }
}
