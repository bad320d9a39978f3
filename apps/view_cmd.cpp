// `penumbra view`: checks the options and the files before a window opens; the window is
// view/viewer.cpp.
#include "view_cmd.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "cli_enums.hpp"
#include "io/image_io.hpp"
#include "io/json_reader.hpp"
#include "io/path_util.hpp"
#include "parse.hpp"
#include "penumbra/penumbra.hpp"
#include "render_options.hpp"
#include "view/replay.hpp"
#include "view/viewer.hpp"

namespace sl = penumbra::spaceland;

namespace {

constexpr int kUsage = 2;
constexpr int kFailure = 1;
// The view's default size: the scene camera's, shrunk to fit this (the panel goes beside it).
constexpr int kMaxWidth = 1024, kMaxHeight = 768;

}  // namespace

bool ViewCommand::parsed() const {
  return app->parsed();
}

std::unique_ptr<ViewCommand> add_view_command(CLI::App& app) {
  auto cmd = std::make_unique<ViewCommand>();
  ViewArgs& a = cmd->args;
  cmd->app = app.add_subcommand("view", "Fly through a 3D scene lit by radiance cascades");
  CLI::App* c = cmd->app;
  c->add_option("scene", a.scene, "3D scene file (.json)")->required()->check(non_empty_path());
  std::string methods;
  for (const sl::MethodInfo& m : sl::methods())
    methods += (methods.empty() ? "" : ", ") + std::string(m.name);
  c->add_option("--method", a.method, "Method (switchable in the window): " + methods)
      ->capture_default_str();
  c->add_option("--size", a.size,
                "The view, WxH pixels (default: the scene camera's, within 1024x768)");
  c->add_option("--scale", a.scale,
                "Internal resolution over the view's, in [1/16, 1] (0: chosen for --target-ms)")
      ->check(real_range(0, 1))
      ->capture_default_str();
  c->add_option("--target-ms", a.target_ms,
                "The frame time the automatic internal resolution aims at")
      ->check(real_range(1, 10000))
      ->capture_default_str();
  c->add_option("--upscale", a.upscale,
                "Below the view's resolution: guided (by the view's depth, normals and albedo) or "
                "bilinear")
      ->check(CLI::IsMember({"guided", "bilinear"}))
      ->capture_default_str();
  c->add_flag("!--no-still-full", a.still_full,
              "Keep the internal resolution when the camera stops (default: a still camera gets "
              "a full-resolution frame)");
  c->add_option("--bounces", a.bounces, "Diffuse bounces (1: direct light only)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  c->add_option("--temporal", a.temporal,
                "ssrc, spwi: temporal accumulation over this many frames, each jittered (ssrc's "
                "directions turned, spwi's probes moved) (0: off; docs/VIEWER.md)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  c->add_option("--grid-slabs", a.grid_slabs,
                "grid: where the view needs its grid solved again (the sun moved, the levels "
                "moved), show the last grid while the new one is solved this many probe slabs a "
                "frame (0: off, solved whole; docs/VIEWER.md)")
      ->check(CLI::Range(0, 1 << 20))
      ->capture_default_str();
  c->add_option("--threads", a.threads, "Worker threads (0: all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  c->add_option("--max-memory", a.max_memory, "Refuse work needing more working memory")
      ->capture_default_str();
  add_exposure_option(c, a.exposure, "Display exposure in EV (default: automatic, each frame)");
  c->add_option("--atlas", a.atlas, "surface: view from this baked atlas (`penumbra bake`)");
  c->add_option("--replay", a.replay, "Camera and panel events to play (docs/VIEWER.md)");
  c->add_option("--record", a.record, "Write this session's camera and panel events at exit");
  c->add_option("--screenshot", a.screenshot,
                "Save the window as PNG once the last view is shown, then exit");
  c->add_option("--save", a.save,
                "At exit, save the view: the scene file with this camera (and sun), and print "
                "the render command for it");
  c->add_option("--frames", a.frames,
                "Render continuously and exit after this many frames (measurement)")
      ->check(CLI::Range(0, 1 << 20));
  c->add_flag("--stats", a.stats, "At exit, print the median frame time per stage");
  return cmd;
}

int run_view(const ViewArgs& args) {
  const ViewArgs& a = args;
  // The viewer flies through 3D scenes; a 2D one gets a message that says so.
  const penumbra::Expected<int> dims = sl::scene_dimensions(a.scene);
  if (!dims) {
    std::cerr << "penumbra view: " << dims.error().message << "\n";
    return kFailure;
  }
  if (*dims != 3) {
    std::cerr << "penumbra view: " << a.scene
              << ": a 2D scene; the viewer flies through 3D scenes (paint it with `penumbra "
                 "paint`)\n";
    return kFailure;
  }
  viewer::Settings settings;
  sl::RenderOptions& o = settings.options;
  o.method = sl::Method::ssrc;
  bool known = false;
  for (const sl::MethodInfo& m : sl::methods())
    if (a.method == m.name) {
      o.method = m.method;
      known = true;
    }
  if (!known) {
    std::cerr << "penumbra view: --method " << a.method << ": expected one of";
    for (const sl::MethodInfo& m : sl::methods()) std::cerr << " " << m.name;
    std::cerr << "\n";
    return kUsage;
  }
  o.pt.spp = 4;  // a quick look, not a reference
  o.bounces = a.bounces;
  o.threads = a.threads;
  if (!parse_bytes(a.max_memory, o.max_memory)) {
    std::cerr << "penumbra view: --max-memory: expected a size such as 512M or 8G, found '"
              << a.max_memory << "'\n";
    return kUsage;
  }
  if (a.scale != 0 && a.scale < 1.0f / 16) {
    std::cerr << "penumbra view: --scale: expected 0 (automatic) or a scale in [1/16, 1], found "
              << a.scale << "\n";
    return kUsage;
  }
  settings.scale = a.scale;
  settings.target_ms = a.target_ms;
  settings.guided = a.upscale == "guided";
  settings.temporal = a.temporal;
  settings.grid_slabs = a.grid_slabs;
  settings.exposure = a.exposure;
  if (!a.atlas.empty() && o.method != sl::Method::surface) {
    std::cerr << "penumbra view: --atlas applies to --method surface only, not "
              << sl::to_string(o.method) << "\n";
    return kUsage;
  }
  if (penumbra::Status s = sl::check_options(o); !s) {
    std::cerr << "penumbra view: " << with_flags(s.error().message) << "\n";
    return kUsage;
  }
  // Outputs: names checked, places writable, no two the same file.
  if (!a.screenshot.empty() && penumbra::io::lowercase_extension(a.screenshot) != ".png") {
    std::cerr << "penumbra view: --screenshot: " << a.screenshot << ": expected a .png name\n";
    return kUsage;
  }
  if (!a.save.empty() && penumbra::io::lowercase_extension(a.save) != ".json") {
    std::cerr << "penumbra view: --save: " << a.save << ": expected a .json name\n";
    return kUsage;
  }
  std::vector<std::pair<std::string, std::string>> outputs;
  if (!a.screenshot.empty()) outputs.push_back({"--screenshot", a.screenshot});
  if (!a.record.empty()) outputs.push_back({"--record", a.record});
  if (!a.save.empty()) outputs.push_back({"--save", a.save});
  auto canonical = [](const std::string& p) {
    std::error_code ec;
    std::filesystem::path c = std::filesystem::weakly_canonical(p, ec);
    return ec ? std::filesystem::path(p) : c;
  };
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    if (penumbra::Status s = penumbra::check_output(outputs[i].second); !s) {
      std::cerr << "penumbra view: " << outputs[i].first << ": " << s.error().message << "\n";
      return kFailure;
    }
    for (std::size_t j = 0; j < i; ++j)
      if (canonical(outputs[i].second) == canonical(outputs[j].second)) {
        std::cerr << "penumbra view: " << outputs[j].first << " and " << outputs[i].first
                  << " would both write " << outputs[i].second << "\n";
        return kUsage;
      }
    if (canonical(outputs[i].second) == canonical(a.scene)) {
      std::cerr << "penumbra view: " << outputs[i].first << " would overwrite the scene file "
                << a.scene << "\n";
      return kUsage;
    }
  }
  viewer::Replay replay;
  if (!a.replay.empty()) {
    penumbra::Expected<viewer::Replay> r = viewer::load_replay(a.replay);
    if (!r) {
      std::cerr << "penumbra view: " << r.error().message << "\n";
      return kFailure;
    }
    replay = std::move(*r);
  }

  penumbra::Expected<sl::Scene> scene = sl::load_scene(a.scene, {o.max_memory});
  if (!scene) {
    std::cerr << "penumbra view: " << with_flags(scene.error().message) << "\n";
    return kFailure;
  }
  // The view's size: --size, or the camera's shrunk to fit the screen beside the panel.
  sl::Camera& cam = scene->camera;
  if (!a.size.empty()) {
    int w = 0, h = 0;
    if (!parse_grid_size(a.size, w, h) || w > 4096 || h > 4096) {
      std::cerr << "penumbra view: --size: expected WxH pixels up to 4096x4096 such as 640x480, "
                   "found '"
                << a.size << "'\n";
      return kUsage;
    }
    cam.width = w;
    cam.height = h;
  } else {
    const double fit =
        std::min({1.0, double(kMaxWidth) / cam.width, double(kMaxHeight) / cam.height});
    cam.width = std::max(8, int(std::lround(cam.width * fit)));
    cam.height = std::max(8, int(std::lround(cam.height * fit)));
  }
  // Every replayed setting is checked against this scene before a window opens.
  {
    viewer::Settings s = settings;
    for (std::size_t i = 0; i < replay.events.size(); ++i)
      if (replay.events[i].kind == viewer::Event::Kind::set)
        if (penumbra::Status st = viewer::apply_set(
                replay.events[i].set, a.replay + ": events[" + std::to_string(i) + "].set", s,
                scene->has_sun);
            !st) {
          std::cerr << "penumbra view: " << st.error().message << "\n";
          return kFailure;
        }
  }
  sl::RenderOptions full = o;
  full.surface.atlas = a.atlas;
  if (penumbra::Status s = sl::check_memory(*scene, full); !s) {
    std::cerr << "penumbra view: " << a.scene << ": " << with_flags(s.error().message) << "\n";
    return kFailure;
  }
  if (penumbra::Status s = sl::check_brightness(*scene, full); !s) {
    std::cerr << "penumbra view: " << s.error().message << "\n";
    return kFailure;
  }
  penumbra::Expected<std::string> text = penumbra::io::read_text(a.scene, "the scene file");
  if (!text) {
    std::cerr << "penumbra view: " << text.error().message << "\n";
    return kFailure;
  }
  nlohmann::json doc;
  try {
    doc = penumbra::io::parse_json(*text, a.scene);
  } catch (const penumbra::io::JsonFailure& f) {
    std::cerr << "penumbra view: " << f.message << "\n";
    return kFailure;
  }
  try {
    viewer::Viewer v(a, std::move(*scene), std::move(doc), settings, std::move(replay));
    return v.run();
  } catch (const std::exception& e) {
    std::cerr << "penumbra view: " << e.what() << "\n";
    return kFailure;
  }
}
