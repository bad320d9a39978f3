#include "quality_cmd.hpp"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <tuple>

#include "analysis/study.hpp"
#include "io/image_io.hpp"
#include "penumbra/penumbra.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "render_options.hpp"

namespace fs = std::filesystem;
using namespace penumbra;
using namespace penumbra::flatland;

bool QualityCommand::parsed() const {
  return app->parsed();
}

std::unique_ptr<QualityCommand> add_quality_command(CLI::App& app) {
  auto cmd = std::make_unique<QualityCommand>();
  QualityArgs& a = cmd->args;
  cmd->app = app.add_subcommand(
      "bench-quality",
      "Error against time of every method on a 2D or 3D scene, against a converged path-traced "
      "reference");
  CLI::App* c = cmd->app;
  c->add_option("scene", a.scene, "Scene file (JSON, format 1; 2D or 3D)")->required();
  c->add_option(
       "-o,--out", a.out,
       "Folder for quality.csv/.md/.svg/.png and the montages: {rc,hrc}_vs_reference.png (2D), "
       "{spwi,grid}_vs_reference.png (3D)")
      ->capture_default_str();
  c->add_option("--cache", a.cache, "Folder for cached references (default: <out>/cache)");
  c->add_option("--doc", a.doc,
                "Markdown file (docs/QUALITY.md) whose lines <!-- bench-quality NAME --> and "
                "<!-- /bench-quality NAME --> enclose the table and plot to replace; NAME is the "
                "scene file's name without .json (3d/NAME for a 3D scene)");
  c->add_option("--bounces", a.bounces, "Diffuse bounces for every method")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  c->add_option("--reference-spp", a.reference_spp,
                "Samples per cell (2D) or pixel (3D) of the reference")
      ->check(CLI::Range(16, 1 << 24))
      ->capture_default_str();
  c->add_option("--max-spp", a.max_spp, "Largest sample count on the path-tracer curves")
      ->check(CLI::Range(4, 1 << 20))
      ->capture_default_str();
  c->add_option("--threads", a.threads, "Worker threads (0: all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  c->add_flag("--quick", a.quick,
              "Fewer configurations (curves up to 16 spp, the default cascades only)");
  return cmd;
}

namespace {

int fail(const std::string& what) {
  std::cerr << "penumbra bench-quality: " << what << "\n";
  return 1;
}

}  // namespace

namespace quality_detail {

std::function<void(const RenderProgress&)> reference_progress() {
  if (!isatty(STDERR_FILENO)) return {};
  return [](const RenderProgress& p) {
    std::fprintf(stderr, "\rreference: %llu/%llu spp, %.0f s", (unsigned long long)p.samples,
                 (unsigned long long)p.target, p.elapsed_s);
  };
}

Status StudyOutput::prepare(const std::string& prefix, const std::string& suffix) {
  section = prefix + fs::path(args.scene).stem().string() + suffix;
  if (!args.doc.empty())
    if (Expected<std::string> d = spliced_doc(""); !d) return d.error();
  cache = args.cache.empty() ? (fs::path(args.out) / "cache").string() : args.cache;
  std::error_code ec;
  for (const std::string& dir : {args.out, cache})
    if (fs::create_directories(dir, ec); ec)
      return Error{dir + ": cannot create the folder: " + ec.message()};
  return {};
}

// The document is checked before the minutes of rendering, and read again at the end so that
// edits made meanwhile are kept.
Expected<std::string> StudyOutput::spliced_doc(const std::string& body) const {
  Expected<std::string> text = io::read_text(args.doc);
  if (!text) return text;
  Expected<std::string> spliced = study::splice_section(*text, section, body);
  if (!spliced) return Error{args.doc + ": " + spliced.error().message};
  return spliced;
}

int StudyOutput::finish(std::vector<study::Row>& rows, study::Reference& ref,
                        const std::vector<Montage>& montages) const {
  study::add_equal_error_times(rows);
  // The reference's own error, extrapolated along the NEE curve from its last point.
  const double k = study::convergence_order(rows, "pt nee");
  for (const study::Row& r : rows)
    if (r.curve == "pt nee" && std::isfinite(k))
      ref.estimated_rel = r.error.relative_rmse * std::pow(double(r.samples) / ref.spp, k);

  const fs::path out(args.out);
  const std::string title = fs::path(args.scene).filename().string() + ": error against time";
  const std::string table = study::to_markdown(rows, args.scene, ref);
  std::vector<std::pair<std::string, std::string>> files = {
      {(out / "quality.csv").string(), study::to_csv(rows)},
      {(out / "quality.md").string(), table},
      {(out / "quality.svg").string(), study::to_svg(rows, title)}};
  if (Status s = io::write_text_files(files); !s) return fail(s.error().message);
  for (const auto& [path, text] : files) std::printf("wrote %s\n", path.c_str());
  // Pictures to look at: the plot, and the montages of the default methods.
  std::vector<std::pair<std::string, ImageRgb8>> pictures = {
      {(out / "quality.png").string(), study::to_png_plot(rows, title)}};
  for (const Montage& m : montages) pictures.push_back({(out / m.file).string(), m.picture});
  if (Status s = write_pictures(pictures); !s) return fail(s.error().message);
  for (const auto& [path, picture] : pictures) std::printf("wrote %s\n", path.c_str());
  // The document last, once everything it links to is there: the table, then the plot and the
  // montages linked by paths relative to the document.
  if (!args.doc.empty()) {
    const fs::path dir = fs::relative(out, fs::absolute(args.doc).parent_path());
    std::string body = table + "\n![" + section + ": error against time](" +
                       (dir / "quality.png").generic_string() + ")\n";
    for (const Montage& m : montages)
      body += "\n![" + section + ": " + m.caption + "](" + (dir / m.file).generic_string() + ")\n";
    Expected<std::string> text = spliced_doc(body);
    if (!text) return fail(text.error().message);
    if (Status s = io::write_text_files({{args.doc, *text}}); !s) return fail(s.error().message);
    std::printf("updated %s\n", args.doc.c_str());
  }
  return 0;
}

}  // namespace quality_detail

int run_quality(const QualityArgs& a) {
  Expected<int> dims = spaceland::scene_dimensions(a.scene);
  if (!dims) return fail(dims.error().message);
  if (*dims == 3) return run_quality3d(a);
  Expected<SceneDesc> desc = load_scene(a.scene);
  if (!desc) return fail(desc.error().message);
  RenderOptions probe;
  probe.threads = a.threads;
  probe.bounces = a.bounces;
  if (Status s = check_brightness(*desc, probe); !s) return fail(s.error().message);
  if (Status s = check_memory(desc->width, desc->height, probe, true); !s)
    return fail(a.scene + ": " + with_flags(s.error().message));
  Expected<Scene> scene = build_scene(*desc);
  if (!scene) return fail(scene.error().message);
  quality_detail::StudyOutput output{a};
  if (Status s = output.prepare(); !s) return fail(s.error().message);

  // The reference: the path tracer with NEE, cached under a name that holds everything it
  // depends on. Its seed differs from the curves' so their errors are independent of its own.
  study::Reference ref;
  ref.spp = a.reference_spp;
  char name[128];
  std::snprintf(name, sizeof name, "pt-nee-%016" PRIx64 "-b%d-%dspp.pfm", study::scene_hash(*scene),
                a.bounces, a.reference_spp);
  ref.path = (fs::path(output.cache) / name).string();
  ImageRgb reference;
  if (fs::exists(ref.path)) {
    Expected<io::RawImage> raw = io::read_image(ref.path, scene->width, scene->height);
    if (!raw || raw->channels != 3)
      return fail(ref.path + ": unreadable cached reference; delete it");
    reference = ImageRgb(scene->width, scene->height, std::move(raw->pixels));
    std::printf("reference: %s (cached)\n", ref.path.c_str());
  } else {
    RenderOptions o;
    o.method = Method::pt;
    o.pt.nee = true;
    o.pt.spp = a.reference_spp;
    o.pt.seed = 0x5eed;
    o.bounces = a.bounces;
    o.threads = a.threads;
    o.progress = quality_detail::reference_progress();
    std::printf("reference: rendering %d spp with NEE...\n", a.reference_spp);
    std::fflush(stdout);
    Expected<RenderResult> r = render(*scene, o);
    if (isatty(STDERR_FILENO)) std::fprintf(stderr, "\n");
    if (!r) return fail(a.scene + ": " + with_flags(r.error().message));
    if (Status s = io::write_pfm(ref.path, r->fluence); !s) return fail(s.error().message);
    ref.time_ms = r->time_ms;
    reference = std::move(r->fluence);
    std::printf("reference: %s (%.1f s)\n", ref.path.c_str(), ref.time_ms / 1e3);
  }

  const std::vector<std::uint8_t> mask = non_opaque_cells(*scene);
  std::vector<study::Row> rows;
  std::vector<quality_detail::Montage> montages;
  for (const study::Run& run : study::default_runs(a.bounces, a.max_spp, a.quick)) {
    RenderOptions o = run.options;
    o.threads = a.threads;
    Expected<RenderResult> r = render(*scene, o);
    if (!r) return fail(a.scene + ": " + run.label + ": " + with_flags(r.error().message));
    Expected<ErrorMetrics> m = compare_images(r->fluence, reference, &mask);
    if (!m) return fail(run.label + ": " + m.error().message);
    study::Row row{run.label, run.curve, to_string(run.options.method), r->time_ms, r->samples, *m};
    std::printf("  %-24s %9.0f ms  rel. RMSE %8.4f%%  PSNR %5.1f dB\n", run.label.c_str(),
                row.time_ms, 100 * m->relative_rmse, m->psnr);
    std::fflush(stdout);
    rows.push_back(row);
    // Pictures of the default cascades against the reference.
    for (const auto& [label, file, caption] :
         {std::tuple{"rc (defaults)", "rc_vs_reference.png",
                     "the default cascades against the "
                     "reference"},
          std::tuple{"hrc (defaults)", "hrc_vs_reference.png",
                     "holographic cascades against the reference"}}) {
      if (run.label != label) continue;
      MontageOptions mo;
      mo.test_label = label;
      mo.reference_label = "path tracer + NEE, " + std::to_string(a.reference_spp) + " spp";
      mo.scene = &*scene;
      Expected<ImageRgb8> montage = comparison_montage(r->fluence, reference, &mask, mo);
      if (!montage) return fail(montage.error().message);
      montages.push_back({file, caption, std::move(*montage)});
    }
  }
  return output.finish(rows, ref, montages);
}
