// `penumbra compare TEST REF [--scene SCENE] [--json] [--heatmap OUT.png] [--montage OUT.png]`
#include "compare_cmd.hpp"

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli_enums.hpp"
#include "io/image_io.hpp"
#include "io/path_util.hpp"
#include "parse.hpp"
#include "penumbra/penumbra.hpp"

namespace {

constexpr int kUsage = 2;
constexpr int kFailure = 1;

int fail(int code, const std::string& message) {
  std::cerr << "penumbra compare: " << message << "\n";
  return code;
}

std::string size_text(int w, int h) {
  return std::to_string(w) + "x" + std::to_string(h);
}

// A linear image: PNG holds display values (tone-mapped, sRGB), so it is refused.
penumbra::Expected<penumbra::ImageRgb> read_linear(const std::string& path,
                                                   std::uint64_t max_bytes) {
  if (penumbra::io::lowercase_extension(path) == ".png")
    return penumbra::Error{path +
                           ": PNG holds display-encoded values, not linear ones; compare the "
                           ".pfm or .exr files (penumbra render -o out.pfm)"};
  penumbra::Expected<penumbra::ImageRgb> image = penumbra::read_rgb_image(path, max_bytes);
  if (!image) return image;
  if (penumbra::Status s = penumbra::check_finite(*image, path); !s) return s.error();
  return image;
}

// Names the flag that sets the memory limit in a reader's message.
std::string with_limit(std::string message) {
  const std::string limit = "the memory limit of";
  const std::size_t at = message.find(limit);
  if (at != std::string::npos)
    message.replace(at, limit.size(), "its share of --max-memory (half),");
  return message;
}

// The rectangle [x, x + w) x [y, y + h) of an image, or of a scene's cells.
penumbra::ImageRgb crop_image(const penumbra::ImageRgb& in, int x0, int y0, int w, int h) {
  penumbra::ImageRgb out(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* s = in.data() + (std::size_t(y0 + y) * in.width() + x0 + x) * 3;
      float* d = out.data() + (std::size_t(y) * w + x) * 3;
      d[0] = s[0], d[1] = s[1], d[2] = s[2];
    }
  return out;
}

penumbra::flatland::Scene crop_scene(const penumbra::flatland::Scene& in, int x0, int y0, int w,
                                     int h) {
  penumbra::flatland::Scene out;
  out.width = w;
  out.height = h;
  out.environment = in.environment;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = in.index(x0 + x, y0 + y);
      out.opacity.push_back(in.opacity[i]);
      for (int c = 0; c < 3; ++c) {
        out.emission.push_back(in.emission[3 * i + c]);
        out.albedo.push_back(in.albedo[3 * i + c]);
      }
    }
  return out;
}

// JSON has no infinity or NaN.
nlohmann::json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

std::string file_name(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

void print_table(const CompareArgs& a, const penumbra::ImageRgb& ref,
                 const penumbra::ErrorMetrics& m, bool radiance) {
  const char* unit = radiance ? "pixels" : "cells";
  const std::uint64_t all = std::uint64_t(ref.width()) * ref.height();
  std::printf("penumbra compare: %s against %s, %s", a.test.c_str(), a.reference.c_str(),
              size_text(ref.width(), ref.height()).c_str());
  if (!a.crop.empty())
    std::printf(" (%s %d..%d x %d..%d)", unit, a.crop[0], a.crop[0] + a.crop[2] - 1, a.crop[1],
                a.crop[1] + a.crop[3] - 1);
  std::printf("\n");
  if (a.scene.empty() || radiance)
    std::printf("  %-16s %llu (all)\n", unit, (unsigned long long)m.cells);
  else
    std::printf("  %-16s %llu of %llu (not opaque in %s)\n", "cells", (unsigned long long)m.cells,
                (unsigned long long)all, a.scene.c_str());
  std::printf("  %-16s %.6g\n", "RMSE", m.rmse);
  if (std::isfinite(m.relative_rmse))
    std::printf("  %-16s %.6g (%.3g%%)\n", "relative RMSE", m.relative_rmse, 100 * m.relative_rmse);
  else
    std::printf("  %-16s inf (the reference mean is not positive)\n", "relative RMSE");
  std::printf("  %-16s %.6g\n", "mean |error|", m.mean_abs);
  std::printf("  %-16s %.6g\n", "max |error|", m.max_abs);
  if (std::isnan(m.psnr))
    std::printf("  %-16s n/a (the reference has no positive value)\n", "PSNR");
  else
    std::printf("  %-16s %.6g dB (peak %.6g: the reference's 99th percentile)\n", "PSNR", m.psnr,
                m.psnr_peak);  // prints "inf dB" for identical images
  std::printf("  %-16s %+.6g (test - reference)\n", "bias", m.bias);
  std::printf("  %-16s %.6g\n", "reference mean", m.reference_mean);
  if (!a.heatmap.empty()) std::printf("  wrote %s\n", a.heatmap.c_str());
  if (!a.montage.empty()) std::printf("  wrote %s\n", a.montage.c_str());
}

int compare(const CompareArgs& a) {
  std::vector<std::string> outputs;
  for (const std::string* out : {&a.heatmap, &a.montage}) {
    if (out->empty()) continue;
    if (penumbra::io::lowercase_extension(*out) != ".png")
      return fail(kUsage, *out + ": pictures are written as PNG (use a .png file name)");
    outputs.push_back(*out);
  }
  if (outputs.size() == 2 && std::filesystem::path(a.heatmap).lexically_normal() ==
                                 std::filesystem::path(a.montage).lexically_normal())
    return fail(kUsage, a.heatmap + ": --heatmap and --montage name the same file");
  if (!(a.heatmap_scale >= 0) || !std::isfinite(a.heatmap_scale))
    return fail(kUsage, "--heatmap-scale: expected a finite number >= 0 (0: automatic)");
  // Refuse unwritable outputs before reading anything.
  for (const std::string& out : outputs)
    if (penumbra::Status s = penumbra::check_output(out); !s)
      return fail(kFailure, s.error().message);

  std::uint64_t max_memory = 0;
  if (!parse_bytes(a.max_memory, max_memory))
    return fail(kUsage,
                "--max-memory: expected a size such as 512M or 8G, found '" + a.max_memory + "'");
  // Each image's reading may take half the limit, refused from its header (two 16384^2 PFMs
  // ended in bad_alloc at 5.1 GiB).
  penumbra::Expected<penumbra::ImageRgb> test = read_linear(a.test, max_memory / 2);
  if (!test) return fail(kFailure, with_limit(test.error().message));
  penumbra::Expected<penumbra::ImageRgb> ref = read_linear(a.reference, max_memory / 2);
  if (!ref) return fail(kFailure, with_limit(ref.error().message));
  const int w = ref->width(), h = ref->height();
  if (test->width() != w || test->height() != h)
    return fail(kFailure, a.test + ": the image is " + size_text(test->width(), test->height()) +
                              " but " + a.reference + " is " + size_text(w, h));

  // The crop is checked against the images before the scene is rasterised.
  const bool cropped = !a.crop.empty();
  if (cropped) {
    const int x0 = a.crop[0], y0 = a.crop[1], cw = a.crop[2], ch = a.crop[3];
    if (x0 < 0 || y0 < 0 || cw < 1 || ch < 1 || std::int64_t(x0) + cw > w ||
        std::int64_t(y0) + ch > h)
      return fail(kFailure, "--crop " + std::to_string(x0) + " " + std::to_string(y0) + " " +
                                std::to_string(cw) + " " + std::to_string(ch) +
                                ": expected X Y W H with W, H >= 1 inside the " + size_text(w, h) +
                                " images");
  }
  std::optional<penumbra::flatland::Scene> scene;
  std::vector<std::uint8_t> mask;
  bool radiance = a.radiance;
  // Without --scene or --radiance, EXRs that say they hold 3D radiance (render writes it in
  // their header) are compared as such; a PFM cannot say, and is taken for 2D fluence.
  if (a.scene.empty() && !a.radiance) {
    const std::string test_world = penumbra::io::image_world(a.test);
    const std::string ref_world = penumbra::io::image_world(a.reference);
    radiance = test_world == "3d radiance" && ref_world == "3d radiance";
    if (!radiance && !a.quiet && (test_world.empty() || ref_world.empty()))
      std::cerr << "penumbra compare: note: compared as 2D fluence (cells); a PFM or an EXR "
                   "without Penumbra's header cannot say it is 3D: --radiance or --scene for a "
                   "3D render\n";
  }
  if (!a.scene.empty()) {
    penumbra::Expected<int> dims = penumbra::spaceland::scene_dimensions(a.scene);
    if (!dims) return fail(kFailure, dims.error().message);
    radiance = radiance || *dims == 3;
  }
  if (!a.scene.empty() && radiance) {
    // A 3D scene names the world and the image size; every pixel counts.
    penumbra::Expected<penumbra::spaceland::Scene> s3 = penumbra::spaceland::load_scene(a.scene);
    if (!s3) return fail(kFailure, s3.error().message);
    if (s3->camera.width != w || s3->camera.height != h)
      return fail(kFailure, a.scene + ": the camera's image is " +
                                size_text(s3->camera.width, s3->camera.height) +
                                " but the images are " + size_text(w, h));
  } else if (!a.scene.empty()) {
    penumbra::Expected<penumbra::flatland::SceneDesc> desc =
        penumbra::flatland::load_scene(a.scene);
    if (!desc) return fail(kFailure, desc.error().message);
    // Checked before rasterising, which for a large scene takes a while.
    if (desc->width != w || desc->height != h)
      return fail(kFailure, a.scene + ": the scene is " + size_text(desc->width, desc->height) +
                                " but the images are " + size_text(w, h));
    penumbra::Expected<penumbra::flatland::Scene> built = penumbra::flatland::build_scene(*desc);
    if (!built) return fail(kFailure, built.error().message);
    scene = std::move(*built);
  }
  if (cropped) {
    const int x0 = a.crop[0], y0 = a.crop[1], cw = a.crop[2], ch = a.crop[3];
    *test = crop_image(*test, x0, y0, cw, ch);
    *ref = crop_image(*ref, x0, y0, cw, ch);
    if (scene) scene = crop_scene(*scene, x0, y0, cw, ch);
  }
  if (scene) mask = penumbra::flatland::non_opaque_cells(*scene);
  const std::vector<std::uint8_t>* counted = scene ? &mask : nullptr;

  penumbra::Expected<penumbra::ErrorMetrics> m = penumbra::compare_images(*test, *ref, counted);
  if (!m) return fail(kFailure, (scene ? a.scene + ": " : "") + m.error().message);

  std::vector<std::pair<std::string, penumbra::ImageRgb8>> pictures;
  if (!a.heatmap.empty()) {
    penumbra::Expected<penumbra::ImageRgb8> p =
        penumbra::error_heatmap(*test, *ref, counted, {a.heatmap_scale});
    if (!p) return fail(kFailure, a.heatmap + ": " + p.error().message);
    pictures.emplace_back(a.heatmap, std::move(*p));
  }
  if (!a.montage.empty()) {
    penumbra::flatland::MontageOptions o;
    o.test_label = "test: " + file_name(a.test);
    o.reference_label = "reference: " + file_name(a.reference);
    o.scene = scene ? &*scene : nullptr;
    o.radiance = radiance;
    o.display.exposure =
        a.exposure ? *a.exposure
        : radiance ? penumbra::spaceland::auto_exposure(*ref, penumbra::spaceland::Aov::radiance)
                   : penumbra::flatland::auto_exposure(*ref, o.scene);
    o.heatmap.scale = a.heatmap_scale;
    penumbra::Expected<penumbra::ImageRgb8> p =
        penumbra::flatland::comparison_montage(*test, *ref, counted, o);
    if (!p) return fail(kFailure, a.montage + ": " + p.error().message);
    pictures.emplace_back(a.montage, std::move(*p));
  }
  // Both pictures or neither.
  if (penumbra::Status s = penumbra::write_pictures(pictures); !s)
    return fail(kFailure, s.error().message);

  if (a.json) {
    nlohmann::json j = {
        {"test", a.test},
        {"reference", a.reference},
        {"scene", a.scene.empty() ? nlohmann::json(nullptr) : nlohmann::json(a.scene)},
        {"radiance", radiance},
        {"width", w},
        {"height", h},
        {"crop", cropped ? nlohmann::json(a.crop) : nlohmann::json(nullptr)},
        {"cells", m->cells},
        {"rmse", m->rmse},
        {"relative_rmse", number_or_null(m->relative_rmse)},
        {"mean_abs", m->mean_abs},
        {"max_abs", m->max_abs},
        {"psnr", number_or_null(m->psnr)},
        {"psnr_peak", m->psnr_peak},
        {"bias", m->bias},
        {"reference_mean", m->reference_mean}};
    std::cout << j.dump(2) << "\n";
  } else if (!a.quiet) {
    print_table(a, *ref, *m, radiance);
  }
  return 0;
}

}  // namespace

bool CompareCommand::parsed() const {
  return app->parsed();
}

std::unique_ptr<CompareCommand> add_compare_command(CLI::App& app) {
  auto cmd = std::make_unique<CompareCommand>();
  CompareArgs& a = cmd->args;
  CLI::App* c = app.add_subcommand(
      "compare", "Error metrics of a linear image (PFM/EXR) against a reference, with pictures");
  c->add_option("test", a.test, "The image to judge (.pfm or .exr)")->required();
  c->add_option("reference", a.reference, "The reference image, of the same size")->required();
  c->add_option("--scene", a.scene,
                "2D: count only the cells this scene leaves not opaque; 3D: the images are its "
                "camera's radiance (as --radiance), every pixel counted");
  c->add_flag("--radiance", a.radiance,
              "The images are 3D radiance: the montage shows them as 3D PNGs do (no 1/2pi)");
  c->add_flag("--json", a.json, "Print one JSON object with the metrics");
  c->add_option("--heatmap", a.heatmap, "Write the signed error with a colour bar (.png)");
  c->add_option("--montage", a.montage, "Write test, reference and error side by side (.png)");
  c->add_option("--heatmap-scale", a.heatmap_scale,
                "Error of the end colours of the heatmap and the montage's error panel (default "
                "0: the 99th percentile of the cells' |error|; larger errors saturate)");
  add_exposure_option(c, a.exposure,
                      "Montage exposure in EV (default: automatic, from the reference, as "
                      "render's PNGs)");
  c->add_option("--crop", a.crop, "Compare only the cells X Y W H (metrics and pictures)")
      ->expected(4);
  c->add_option("--max-memory", a.max_memory,
                "Refuse images whose reading needs more memory (each may take half)")
      ->capture_default_str();
  c->add_flag("-q,--quiet", a.quiet, "Print nothing on success");
  cmd->app = c;
  return cmd;
}

int run_compare(const CompareArgs& args) {
  try {
    return compare(args);
  } catch (const std::exception& e) {  // the library reports errors as values; this is a bug
    return fail(kFailure, std::string("internal error: ") + e.what());
  }
}
