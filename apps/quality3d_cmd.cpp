// `penumbra bench-quality` on a 3D scene: the path tracer's curve (1, 4, 16, ... samples per
// pixel), SPWI and the probe grid at their defaults and each variant docs/QUALITY.md studies,
// against the path tracer at --reference-spp, as error against time, at --bounces.
#include <unistd.h>

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>

#include "io/image_io.hpp"
#include "io/json_reader.hpp"
#include "penumbra/penumbra.hpp"
#include "quality_cmd.hpp"

namespace fs = std::filesystem;
using namespace penumbra;
namespace sl = penumbra::spaceland;

namespace {

int fail(const std::string& what) {
  std::cerr << "penumbra bench-quality: " << what << "\n";
  return 1;
}

// A 64-bit hash (FNV-1a) of everything that determines a 3D scene's image, to name cached
// references: the camera, the sky and sun, the materials and textures, every surface and medium.
std::uint64_t scene_hash(const sl::Scene& scene) {
  std::uint64_t h = 1469598103934665603ull;
  auto bytes = [&](const void* p, std::size_t n) {
    const unsigned char* c = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ c[i]) * 1099511628211ull;
  };
  auto array = [&](const auto& v) { bytes(v.data(), v.size() * sizeof(v[0])); };
  auto values = [&](const auto&... v) { (bytes(&v, sizeof v), ...); };
  const sl::Camera& c = scene.camera;
  values(c.position, c.look_at, c.up, c.fov_y, c.width, c.height);
  values(scene.sky.zenith, scene.sky.horizon, scene.sky.ground, scene.has_sun);
  if (scene.has_sun) values(scene.sun.direction, scene.sun.irradiance, scene.sun.angular_radius);
  for (const sl::Material& m : scene.materials) values(m.albedo, m.emission, m.albedo_texture);
  for (const sl::Texture& t : scene.textures) {
    values(t.width, t.height, t.wrap_s, t.wrap_t, t.nearest);
    array(t.rgb);
  }
  for (const sl::TriangleMesh& m : scene.meshes) {
    array(m.positions);
    array(m.normals);
    array(m.uvs);
    array(m.triangles);
    array(m.materials);
  }
  for (const sl::Sphere& s : scene.spheres) values(s.center, s.radius, s.material);
  for (const sl::Disk& d : scene.disks) values(d.center, d.normal, d.radius, d.material);
  for (const sl::Medium& m : scene.media) bytes(&m, sizeof m);
  return h;
}

// One configuration. `derive`, when set, changes the options from what the method's defaults
// used (derived lengths are known once they have run, which come first) and returns what to add
// to the label.
using Derive = std::function<std::string(sl::RenderOptions&, const sl::RenderOptions& defaults)>;
struct Run {
  std::string label, curve;
  sl::RenderOptions options;
  Derive derive;
  bool defaults = false;  // the method at its defaults: what the others derive from
};

// A run of `method` with `set` applied to its options (`member` of the render options).
template <class Options, class Set>
void add_run(std::vector<Run>& runs, sl::Method method, Options sl::RenderOptions::*member,
             const std::string& label, Set&& set, Derive derive = {}) {
  sl::RenderOptions o;
  o.method = method;
  set(o.*member);
  runs.push_back({label, "", o, std::move(derive)});
}

// A derived length (t0, the voxel; `field` picks it) at `k` times the defaults', shown as `flag`.
template <class Field>
Derive scaled(double k, Field field, const char* flag) {
  return [k, field, flag](sl::RenderOptions& o, const sl::RenderOptions& d) {
    float& v = field(o);
    v = float(k * field(d));
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on a chain of +.
    std::string label = " ";
    label += io::format_rounded(k);
    label += "x (";
    label += flag;
    label += " ";
    label += io::format_rounded(v);
    label += ")";
    return label;
  };
}

// The probe grid at its defaults, then (unless quick) the voxel at half and twice its size, s0
// and Q0 each way, t0 at half and twice, the bilinear fix and interval extension.
void add_grid_runs(std::vector<Run>& runs, bool quick) {
  auto grid = [&](const std::string& label, auto&& set, Derive derive = {}) {
    add_run(runs, sl::Method::grid, &sl::RenderOptions::grid, label, set, std::move(derive));
  };
  using G = sl::GridOptions;
  grid("grid (defaults)", [](G&) {});
  runs.back().defaults = true;
  if (quick) return;
  for (double k : {0.5, 2.0})
    grid(
        "grid voxel", [](G&) {},
        scaled(
            k, [](auto& o) -> auto& { return o.grid.voxel; }, "--voxel"));
  grid("grid --probe-spacing 1", [](G& g) { g.probe_spacing = 1; });
  grid("grid --probe-spacing 4", [](G& g) { g.probe_spacing = 4; });
  grid("grid --directions 64", [](G& g) { g.directions = 64; });
  for (double k : {0.5, 2.0})
    grid(
        "grid t0", [](G&) {},
        scaled(
            k, [](auto& o) -> auto& { return o.grid.interval; }, "--interval"));
  grid("grid --fix bilinear", [](G& g) { g.fix = true; });
  grid("grid --extend", [](G& g) { g.extend_length = 8; });
}

// The path tracer at 1, 4, 16, ... samples per pixel, SPWI at its defaults, then (unless quick)
// each merge, t0 from 0.25x to 2x, s0 and Q0 each way, pre-averaging, the thesis'
// disjoint intervals and its gather without normals, the per-probe gather, branching 16, the
// depth bias, the bilateral thresholds and one cascade fewer and more, and a dense setting; then
// the probe grid's runs.
std::vector<Run> default_runs(int max_spp, bool quick) {
  std::vector<Run> runs;
  for (int spp = 1; spp <= max_spp; spp *= 4) {
    if (quick && spp > 16) break;
    sl::RenderOptions o;
    o.pt.spp = spp;
    runs.push_back({"pt " + std::to_string(spp) + " spp", "pt nee", o, {}});
  }
  auto spwi = [&](const std::string& label, auto&& set, Derive derive = {}) {
    add_run(runs, sl::Method::spwi, &sl::RenderOptions::spwi, label, set, std::move(derive));
  };
  using S = sl::SpwiOptions;
  spwi("spwi (defaults)", [](S&) {});
  runs.back().defaults = true;
  if (quick) {
    add_grid_runs(runs, true);
    return runs;
  }
  for (sl::SpwiMerge m : {sl::SpwiMerge::bilinear, sl::SpwiMerge::bilateral, sl::SpwiMerge::fix,
                          sl::SpwiMerge::minmax})
    spwi(std::string("spwi --merge ") + sl::to_string(m), [m](S& s) { s.merge = m; });
  for (double k : {0.25, 0.5, 2.0})
    spwi(
        "spwi t0", [](S&) {},
        scaled(
            k, [](auto& o) -> auto& { return o.spwi.interval; }, "--interval"));
  spwi("spwi --probe-spacing 2", [](S& s) { s.probe_spacing = 2; });
  spwi("spwi --probe-spacing 8", [](S& s) { s.probe_spacing = 8; });
  spwi("spwi --directions 16", [](S& s) { s.directions = 16; });
  spwi("spwi --directions 256", [](S& s) { s.directions = 256; });
  spwi("spwi --preaverage", [](S& s) { s.preaverage = true; });
  spwi("spwi --disjoint", [](S& s) { s.overlap = false; });
  spwi("spwi --gather-normal 0", [](S& s) { s.gather_normal = 0; });
  spwi("spwi --gather probe", [](S& s) { s.gather = sl::SpwiGather::probe; });
  spwi("spwi --branching 16", [](S& s) { s.branching = 16; });
  // The thresholds and the bias the thesis picked by hand, and the derived cascade count.
  spwi("spwi --depth-bias 0.98", [](S& s) { s.depth_bias = 0.98f; });
  spwi("spwi --gather-edge 0.025", [](S& s) { s.gather_edge = 0.025f; });
  spwi("spwi --gather-edge 0.1", [](S& s) { s.gather_edge = 0.1f; });
  spwi("spwi --merge bilateral --merge-edge 0.05", [](S& s) {
    s.merge = sl::SpwiMerge::bilateral;
    s.merge_edge = 0.05f;
  });
  spwi("spwi --merge bilateral --merge-edge 0.2", [](S& s) {
    s.merge = sl::SpwiMerge::bilateral;
    s.merge_edge = 0.2f;
  });
  for (int delta : {-1, 1})
    spwi(
        "spwi cascades", [](S&) {},
        [delta](sl::RenderOptions& o, const sl::RenderOptions& d) {
          o.spwi.cascades = std::max(1, d.spwi.cascades + delta);
          std::string label = delta > 0 ? " +" : " ";
          label += std::to_string(delta);
          label += " (--cascades ";
          label += std::to_string(o.spwi.cascades);
          label += ")";
          return label;
        });
  spwi("spwi --probe-spacing 2 --directions 256", [](S& s) {
    s.probe_spacing = 2;
    s.directions = 256;
  });
  add_grid_runs(runs, false);
  return runs;
}

}  // namespace

int run_quality3d(const QualityArgs& a) {
  Expected<sl::Scene> scene = sl::load_scene(a.scene);
  if (!scene) return fail(scene.error().message);
  quality_detail::StudyOutput output{a};
  // One section per scene and bounce count.
  if (Status s = output.prepare("3d/", a.bounces > 1 ? "-b" + std::to_string(a.bounces) : ""); !s)
    return fail(s.error().message);
  const int w = scene->camera.width, h = scene->camera.height;

  // The reference, cached under a name that holds everything it depends on; its seed differs
  // from the curve's so that their errors are independent.
  study::Reference ref;
  ref.spp = a.reference_spp;
  ref.unit = "pixel";
  char name[128];
  std::snprintf(name, sizeof name, "pt3d-%016" PRIx64 "-b%d-%dspp.pfm", scene_hash(*scene),
                a.bounces, a.reference_spp);
  ref.path = (fs::path(output.cache) / name).string();
  ImageRgb reference;
  if (fs::exists(ref.path)) {
    Expected<io::RawImage> raw = io::read_image(ref.path, w, h);
    if (!raw || raw->channels != 3)
      return fail(ref.path + ": unreadable cached reference; delete it");
    reference = ImageRgb(w, h, std::move(raw->pixels));
    std::printf("reference: %s (cached)\n", ref.path.c_str());
  } else {
    sl::RenderOptions o;
    o.pt.spp = a.reference_spp;
    o.bounces = a.bounces;
    o.pt.seed = 0x5eed;
    o.threads = a.threads;
    o.progress = quality_detail::reference_progress();
    std::printf("reference: rendering %d spp...\n", a.reference_spp);
    std::fflush(stdout);
    Expected<sl::RenderResult> r = sl::render(*scene, o);
    if (isatty(STDERR_FILENO)) std::fprintf(stderr, "\n");
    if (!r) return fail(a.scene + ": " + r.error().message);
    if (Status s = io::write_pfm(ref.path, r->radiance); !s) return fail(s.error().message);
    ref.time_ms = r->time_ms;
    reference = std::move(r->radiance);
    std::printf("reference: %s (%.1f s)\n", ref.path.c_str(), ref.time_ms / 1e3);
  }

  std::vector<study::Row> rows;
  std::vector<quality_detail::Montage> montages;
  std::map<sl::Method, sl::RenderOptions> defaults;  // what each method's defaults used
  std::vector<sl::Method> refused;  // methods whose defaults refused the scene (spwi: fog)
  for (Run& run : default_runs(a.max_spp, a.quick)) {
    sl::RenderOptions o = run.options;
    o.threads = a.threads;
    o.bounces = a.bounces;
    if (std::find(refused.begin(), refused.end(), o.method) != refused.end()) continue;
    if (run.derive) run.label += run.derive(o, defaults.at(o.method));
    Expected<sl::RenderResult> r = sl::render(*scene, o);
    if (!r && run.defaults) {
      // A method that cannot carry the scene (SPWI and fog): its runs are left out, said here.
      std::printf("  %-44s refused: %s\n", run.label.c_str(), r.error().message.c_str());
      refused.push_back(o.method);
      continue;
    }
    if (!r) return fail(a.scene + ": " + run.label + ": " + r.error().message);
    // Every pixel counts: the camera's image, sky included.
    Expected<ErrorMetrics> m = compare_images(r->radiance, reference);
    if (!m) return fail(run.label + ": " + m.error().message);
    study::Row row{run.label, run.curve, sl::to_string(o.method), r->time_ms, r->samples, *m};
    std::printf("  %-44s %9.0f ms  rel. RMSE %8.4f%%  PSNR %5.1f dB\n", run.label.c_str(),
                row.time_ms, 100 * m->relative_rmse, m->psnr);
    std::fflush(stdout);
    rows.push_back(row);
    if (run.defaults) {
      defaults[o.method] = r->options;
      flatland::MontageOptions mo;
      mo.test_label = run.label;
      mo.reference_label = "path tracer, " + std::to_string(a.reference_spp) + " spp";
      mo.radiance = true;
      Expected<ImageRgb8> montage =
          flatland::comparison_montage(r->radiance, reference, nullptr, mo);
      if (!montage) return fail(montage.error().message);
      const std::string method = sl::to_string(o.method);
      montages.push_back({method + "_vs_reference.png",
                          std::string(sl::methods()[std::size_t(o.method)].title) +
                              " at its defaults against the reference",
                          *montage});
    }
  }
  return output.finish(rows, ref, montages);
}
