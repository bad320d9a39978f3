#include "field_cmd.hpp"

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_enums.hpp"
#include "io/path_util.hpp"
#include "parse.hpp"
#include "penumbra/penumbra.hpp"
#include "penumbra/spaceland/field.hpp"
#include "render_options.hpp"

namespace {

constexpr int kUsage = 2;
constexpr int kFailure = 1;

namespace sl = penumbra::spaceland;
using penumbra::Vec3;

int fail(int code, const std::string& message) {
  std::cerr << "penumbra field: " << message << "\n";
  return code;
}

// "x,y,z,ux,uy,uz,vx,vy,vz": nine numbers, nothing else.
bool parse_window(const std::string& text, sl::Window& w) {
  std::vector<float> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    try {
      v.push_back(std::stof(item, &used));
    } catch (const std::exception&) {
      return false;
    }
    if (used != item.size()) return false;
  }
  if (v.size() != 9 || (!text.empty() && text.back() == ',')) return false;
  w.corner = {v[0], v[1], v[2]};
  w.u = {v[3], v[4], v[5]};
  w.v = {v[6], v[7], v[8]};
  return true;
}

// p turned by `angle` radians about the axis through `centre` along unit `axis` (Rodrigues).
Vec3 turned(Vec3 p, Vec3 centre, Vec3 axis, float angle) {
  const Vec3 r = p - centre;
  const float c = std::cos(angle), s = std::sin(angle);
  return centre + r * c + cross(axis, r) * s + axis * (dot(axis, r) * (1 - c));
}

// View k: the scene's camera (k = 0), then turned about the window's centre line along v by
// +15, -15, +30, -30, ... degrees.
sl::Camera view_camera(const sl::Camera& c, const sl::Window& w, int k) {
  if (k == 0) return c;
  const float degrees = 15.0f * float((k + 1) / 2) * (k % 2 ? 1.0f : -1.0f);
  const float angle = degrees * 3.14159265358979f / 180;
  const Vec3 centre = w.corner + w.u * 0.5f + w.v * 0.5f, axis = normalize(w.v);
  sl::Camera out = c;
  out.position = turned(c.position, centre, axis, angle);
  out.look_at = turned(c.look_at, centre, axis, angle);
  out.up = turned(c.position + c.up, centre, axis, angle) - out.position;
  return out;
}

// "`window`: ..." (the library's message, naming the option) -> "--window: ...".
std::string as_flag(const std::string& message) {
  const std::size_t end = message.find('`', 1);
  if (message.empty() || message[0] != '`' || end == std::string::npos) return message;
  return "--" + message.substr(1, end - 1) + message.substr(end + 1);
}

// The covered pixels with no emitter seen within one pixel: a lamp's edge, seen through the
// field at the resolution of the cascade that holds it, differs there by its whole emission.
std::vector<std::uint8_t> away_from_emitters(const std::vector<std::uint8_t>& covered,
                                             const std::vector<std::uint8_t>& emitter, int w,
                                             int h) {
  std::vector<std::uint8_t> out(covered);
  if (emitter.size() != out.size()) return out;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t k = std::size_t(y) * std::size_t(w) + std::size_t(x);
      for (int dy = -1; dy <= 1 && out[k]; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int u = x + dx, v = y + dy;
          if (u >= 0 && u < w && v >= 0 && v < h &&
              emitter[std::size_t(v) * std::size_t(w) + std::size_t(u)]) {
            out[k] = 0;
            break;
          }
        }
    }
  return out;
}

// "view.png" -> "view.<tag>.png".
std::string tagged(const std::string& path, const std::string& tag) {
  const std::string ext = penumbra::io::lowercase_extension(path);
  return path.substr(0, path.size() - ext.size()) + "." + tag +
         path.substr(path.size() - ext.size());
}

}  // namespace

bool FieldCommand::parsed() const {
  return app && app->parsed();
}

std::unique_ptr<FieldCommand> add_field_command(CLI::App& app) {
  auto cmd = std::make_unique<FieldCommand>();
  FieldArgs& a = cmd->args;
  sl::FieldOptions& f = a.field;
  CLI::App* field = app.add_subcommand(
      "field",
      "Path-trace what lies behind a window into its surface radiance cascades, then view it "
      "from cameras that never baked it (the direct radiance field renderer)");
  cmd->app = field;
  field->add_option("scene", a.scene, "3D scene file (.json)")->required();
  field->add_option("-o,--output", a.output, "The view from the scene's camera (.png, .exr, .pfm)")
      ->required();
  field
      ->add_option("--window", a.window,
                   "The window: corner x,y,z, then edges u and v (9 numbers); the field is what "
                   "lies on the side cross(u, v) points to")
      ->required();
  field->add_option("--texels", f.texels, "Cascade 0's probes along the window's longer edge")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  field
      ->add_option("--directions", f.directions,
                   "Q0: cascade 0's directions over the hemisphere (4, 16, 64, ... 4096)")
      ->capture_default_str();
  field->add_option("--interval", f.interval, "t0: cascade 0's interval (0: two texels)")
      ->check(real_range(0, 1e30))
      ->capture_default_str();
  field->add_option("--cascades", f.cascades, "Cascades (0: until an interval spans the scene)")
      ->check(CLI::Range(0, 12))
      ->capture_default_str();
  field->add_option("--spp", f.spp, "Path-traced samples per interval of a probe and direction")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  field->add_flag("!--no-lead-in", f.lead_in,
                  "Plain intervals: no looking back for a surface a lower interval missed");
  field->add_option("--bounces", f.bounces, "Bounces (1: direct light only)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  field->add_option("--seed", f.seed, "Changes every random number")->capture_default_str();
  field
      ->add_option("--views", a.views,
                   "Views: the scene's camera, then cameras turned about the window's centre by "
                   "+15, -15, +30, -30 ... degrees (written as OUTPUT.view<k>.ext)")
      ->check(CLI::Range(1, 9))
      ->capture_default_str();
  field
      ->add_option("--reference", a.reference,
                   "Path-trace each view's window pixels with this many samples a pixel (written "
                   "as .reference) and print the field's error against it (0: none)")
      ->check(CLI::Range(0, 1 << 20))
      ->capture_default_str();
  field->add_option("--width", a.width, "The views' width (the camera's fov_y is kept)")
      ->check(CLI::Range(1, sl::kMaxImageSide));
  field->add_option("--height", a.height, "The views' height")
      ->check(CLI::Range(1, sl::kMaxImageSide));
  field->add_option("--threads", f.threads, "Worker threads (0: all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  field->add_option("--max-memory", a.max_memory, "Refuse work needing more working memory")
      ->capture_default_str();
  field->add_flag("--json", a.json, "Print one JSON object with timings, memory and errors");
  field->add_flag("-q,--quiet", a.quiet, "Print nothing on success");
  return cmd;
}

int run_field(const FieldArgs& a) {
  sl::FieldOptions o = a.field;
  if (!parse_window(a.window, o.window))
    return fail(kUsage, "--window: expected 9 comma-separated numbers (corner, u, v), found '" +
                            a.window + "'");
  if (!parse_bytes(a.max_memory, o.max_memory))
    return fail(kUsage,
                "--max-memory: expected a size such as 512M or 8G, found '" + a.max_memory + "'");
  if (penumbra::Status s = sl::check_field_options(o); !s)
    return fail(kUsage, as_flag(s.error().message));
  std::vector<std::string> paths;
  for (int k = 0; k < a.views; ++k) {
    const std::string view = k == 0 ? a.output : tagged(a.output, "view" + std::to_string(k));
    paths.push_back(view);
    if (a.reference > 0) paths.push_back(tagged(view, "reference"));
  }
  for (const std::string& p : paths) {
    if (!penumbra::is_supported_output(p))
      return fail(kUsage, p + ": expected a .png, .exr or .pfm output");
    if (penumbra::Status s = penumbra::check_output(p); !s)
      return fail(kFailure, s.error().message);
  }

  penumbra::Expected<sl::Scene> scene = sl::load_scene(a.scene, {o.max_memory});
  if (!scene) return fail(kFailure, with_flags(scene.error().message));
  // --width and --height replace the camera's image size; fov_y stays.
  if (a.width > 0) scene->camera.width = a.width;
  if (a.height > 0) scene->camera.height = a.height;
  // Every view (and its reference) is held until the files are written: refused up front.
  const std::uint64_t pixels = std::uint64_t(scene->camera.width) * scene->camera.height;
  // A view: its image and coverage; a reference also marks the emitters, and the comparison
  // makes one more mask.
  const std::uint64_t views_bytes =
      std::uint64_t(a.views) * pixels *
      ((3 * sizeof(float) + 1) + (a.reference > 0 ? 3 * sizeof(float) + 3 : 0));
  const std::uint64_t need =
      views_bytes + sl::estimate_field_memory(*scene, o) + sl::scene_bytes(*scene);
  if (need > o.max_memory)
    return fail(kFailure, a.scene + ": the field, the scene and the views need " +
                              std::to_string(need >> 20) +
                              " MiB of working memory, over the --max-memory limit");
  penumbra::Expected<sl::RadianceField> field = sl::RadianceField::bake(*scene, o);
  if (!field) return fail(kFailure, a.scene + ": " + with_flags(field.error().message));

  struct Shown {
    sl::FieldView view, reference;
    penumbra::ErrorMetrics error, lit;  // over the window's pixels; those seeing no emitter
    bool compared = false, lit_compared = false;
  };
  std::vector<Shown> shown(std::size_t(a.views));
  for (int k = 0; k < a.views; ++k) {
    Shown& s = shown[std::size_t(k)];
    const sl::Camera camera = view_camera(scene->camera, o.window, k);
    penumbra::Expected<sl::FieldView> view = field->view(camera, o.threads);
    if (!view)
      return fail(kFailure, a.scene + ": view " + std::to_string(k) + ": " +
                                with_flags(view.error().message));
    s.view = std::move(*view);
    if (a.reference > 0) {
      penumbra::Expected<sl::FieldView> ref = sl::reference_view(
          *scene, o.window, camera, a.reference, o.bounces, o.seed + 1, o.threads, o.max_memory);
      if (!ref) return fail(kFailure, a.scene + ": " + ref.error().message);
      s.reference = std::move(*ref);
      if (penumbra::Expected<penumbra::ErrorMetrics> e =
              penumbra::compare_images(s.view.radiance, s.reference.radiance, &s.view.covered)) {
        s.error = *e;
        s.compared = true;
      }
      const std::vector<std::uint8_t> lit =
          away_from_emitters(s.view.covered, s.reference.sees_emitter, camera.width, camera.height);
      if (penumbra::Expected<penumbra::ErrorMetrics> e =
              penumbra::compare_images(s.view.radiance, s.reference.radiance, &lit)) {
        s.lit = *e;
        s.lit_compared = true;
      }
    }
  }
  // One exposure for every picture, the scene camera's view's, so that they compare.
  penumbra::DisplayOptions display;
  display.exposure = sl::auto_exposure(shown[0].view.radiance, sl::Aov::radiance);
  for (int k = 0, p = 0; k < a.views; ++k) {
    const Shown& s = shown[std::size_t(k)];
    if (penumbra::Status st = sl::write_images({paths[std::size_t(p++)]}, s.view.radiance,
                                               sl::Aov::radiance, display);
        !st)
      return fail(kFailure, st.error().message);
    if (a.reference > 0)
      if (penumbra::Status st = sl::write_images({paths[std::size_t(p++)]}, s.reference.radiance,
                                                 sl::Aov::radiance, display);
          !st)
        return fail(kFailure, st.error().message);
  }

  const sl::FieldOptions& used = field->options();
  const std::vector<std::uint64_t> stores = field->store_bytes();
  if (a.json) {
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();
    for (const auto& s : field->stages()) stages[s.name] = s.ms;
    nlohmann::ordered_json views = nlohmann::ordered_json::array();
    for (int k = 0; k < a.views; ++k) {
      const Shown& s = shown[std::size_t(k)];
      std::size_t covered = 0;
      for (std::uint8_t c : s.view.covered) covered += c;
      nlohmann::ordered_json v = {{"output", paths[std::size_t(k * (a.reference > 0 ? 2 : 1))]},
                                  {"window_pixels", covered},
                                  {"time_ms", s.view.time_ms}};
      if (s.compared) {
        v["reference_ms"] = s.reference.time_ms;
        v["relative_rmse"] = s.error.relative_rmse;
        v["bias"] = s.error.bias;
        v["reference_mean"] = s.error.reference_mean;
      }
      if (s.lit_compared) v["relative_rmse_without_emitters"] = s.lit.relative_rmse;
      views.push_back(v);
    }
    nlohmann::ordered_json j = {{"scene", a.scene},
                                {"probes_u", field->probes_u()},
                                {"probes_v", field->probes_v()},
                                {"parameters",
                                 {{"texels", used.texels},
                                  {"directions", used.directions},
                                  {"interval", used.interval},
                                  {"cascades", used.cascades},
                                  {"spp", used.spp},
                                  {"lead_in", used.lead_in},
                                  {"bounces", used.bounces},
                                  {"reference_spp", a.reference}}},
                                {"store_bytes", stores},
                                {"stages", stages},
                                {"bake_ms", field->bake_ms()},
                                {"memory_bytes", field->memory_bytes()},
                                {"rays", field->rays()},
                                {"views", views}};
    std::cout << j.dump(2) << "\n";
  } else if (!a.quiet) {
    std::printf(
        "penumbra %s: %s (3D) radiance field: %dx%d probes, Q0 %d, t0 %g, %d cascades, %d spp, "
        "%d bounce(s)\n",
        penumbra::kVersion, a.scene.c_str(), field->probes_u(), field->probes_v(), used.directions,
        double(used.interval), used.cascades, used.spp, used.bounces);
    for (const auto& s : field->stages()) std::printf("  %-24s %9.1f ms\n", s.name.c_str(), s.ms);
    std::printf("  %-24s %9.1f ms\n", "bake", field->bake_ms());
    std::printf("  working memory %.1f MiB, %.1f M rays traced\n",
                double(field->memory_bytes()) / (1 << 20), double(field->rays()) / 1e6);
    for (int k = 0; k < a.views; ++k) {
      const Shown& s = shown[std::size_t(k)];
      std::printf("  view %d: %.1f ms", k, s.view.time_ms);
      if (s.compared)
        std::printf(", relative RMSE %.4f against the path tracer (%d spp, %.1f ms)",
                    s.error.relative_rmse, a.reference, s.reference.time_ms);
      if (s.lit_compared) std::printf(", %.4f away from emitters", s.lit.relative_rmse);
      std::printf(" -> %s\n", paths[std::size_t(k * (a.reference > 0 ? 2 : 1))].c_str());
    }
  }
  return 0;
}
