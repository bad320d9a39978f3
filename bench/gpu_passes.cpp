// Per-pass times of RC and HRC on a device, the figures docs/PERFORMANCE.md sets beside the
// HRC paper's Table 1. Renders the benchmark's lights scene (bench::lights_scene, 102 lights)
// at each size through one Renderer, as the painter does (kernels, scene and buffers stay on
// the device), and reports the median of each pass over the timed runs. For HRC's merge passes
// it also gives the bandwidth their compulsory traffic implies (every T and R element read and
// written once), to set against the card's peak. Passes a warm render skips because the scene
// did not change (upload, medium, distance field) are shown from the first render.
//
//   penumbra_gpu_passes [--sizes 512,1024,2048] [--runs 5] [--method rc|hrc|both]
//                       [--device gpu|cpu] [--storage f32|f16]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bench_scenes.hpp"
#include "core/median.hpp"
#include "core/timer.hpp"
#include "flatland/hrc/hrc.hpp"
#include "penumbra/flatland/render.hpp"
#include "tool_cli.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::flatland;

// Bytes HRC's passes must move at least (4 values per T element, 3 per R element, of `value`
// bytes each), over the four quadrants.
std::map<std::string, double> hrc_traffic(int w, int h, double value) {
  const double te = 4 * value, re = 3 * value;
  const hrc::Sizes sz = hrc::plan(w, h);
  std::map<std::string, double> bytes;
  for (int d = 0; d < 4; ++d) {
    const hrc::View& v = sz.views[d & 1];
    const double view_cells = double(v.w + hrc::kPad) * (v.h + 2 * hrc::kPad);
    double trace = view_cells * 6 * 4;
    for (int n = 0; n <= std::min(2, v.levels); ++n) trace += double(v.t_size(n)) * te;
    double up = 0;
    for (int n = 3; n <= v.levels; ++n) up += double(v.t_size(n - 1) + v.t_size(n)) * te;
    double down = 0;
    for (int n = v.levels - 1; n >= 0; --n)
      down += double(v.t_size(n) + v.t_size(n + 1)) * te +
              double(v.r_size(n + 1) * (n + 1 < v.levels) + v.r_size(n)) * re;
    bytes["gpu trace T0-T2"] += trace;
    bytes["gpu merge up T3-TN"] += up;
    bytes["gpu merge down R"] += down;
  }
  return bytes;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Per-pass times of RC and HRC on the GPU (or the CPU), warm, median of runs",
               "penumbra_gpu_passes"};
  std::vector<int> sizes = {512, 1024, 2048};
  int runs = 5;
  std::string method = "both", device = "gpu", storage = "f32";
  app.add_option("--sizes", sizes, "Grid sides")->delimiter(',')->check(CLI::Range(16, 8192));
  app.add_option("--runs", runs, "Timed renders per case (after one warm-up)")
      ->check(CLI::Range(1, 1000));
  app.add_option("--method", method, "rc, hrc or both")
      ->check(CLI::IsMember({"rc", "hrc", "both"}));
  app.add_option("--device", device, "gpu or cpu")->check(CLI::IsMember({"gpu", "cpu"}));
  app.add_option("--storage", storage, "hrc: f32 or f16 (the paper's)")
      ->check(CLI::IsMember({"f32", "f16"}));
  if (const std::optional<int> stop = penumbra::tool::parse(app, argc, argv)) return *stop;

  std::vector<Method> methods;
  if (method != "hrc") methods.push_back(Method::rc);
  if (method != "rc") methods.push_back(Method::hrc);
  std::printf("| method | grid | device | pass | median ms | GB/s (compulsory traffic) |\n");
  std::printf("| --- | --- | --- | --- | ---: | ---: |\n");
  for (Method m : methods)
    for (int size : sizes) {
      const Scene scene = *build_scene(bench::lights_scene(size, 102));
      RenderOptions o;
      o.method = m;
      o.device = device == "gpu" ? Device::gpu : Device::cpu;
      o.max_memory = std::uint64_t(64) << 30;
      o.hrc.storage = storage == "f16" ? Storage::f16 : Storage::f32;
      Renderer renderer;
      std::map<std::string, std::vector<double>> passes;
      std::vector<std::string> order;
      std::vector<double> wall, total;
      std::string name;
      std::vector<StageTime> first;
      for (int run = 0; run <= runs; ++run) {
        Stopwatch watch;
        Expected<RenderResult> r = renderer.render(scene, o);
        const double ms = watch.ms();
        if (!r) {
          std::fprintf(stderr, "penumbra_gpu_passes: %s %d: %s\n", to_string(m), size,
                       r.error().message.c_str());
          return 1;
        }
        name = r->device;
        if (run == 0) {  // warm-up: pipelines, buffers, the first upload
          first = r->stages;
          continue;
        }
        wall.push_back(ms);
        total.push_back(r->time_ms);
        for (const StageTime& s : r->stages) {
          if (!passes.count(s.name)) order.push_back(s.name);
          passes[s.name].push_back(s.ms);
        }
      }
      const std::map<std::string, double> traffic =
          m == Method::hrc ? hrc_traffic(size, size, storage == "f16" ? 2 : 4)
                           : std::map<std::string, double>{};
      for (const std::string& pass : order) {
        const double ms = median(passes[pass]);
        auto t = traffic.find(pass);
        if (t != traffic.end() && ms > 0)
          std::printf("| %s | %d^2 | %s | %s | %.2f | %.1f |\n", to_string(m), size, name.c_str(),
                      pass.c_str(), ms, t->second / (ms * 1e-3) / 1e9);
        else
          std::printf("| %s | %d^2 | %s | %s | %.2f | |\n", to_string(m), size, name.c_str(),
                      pass.c_str(), ms);
      }
      // Passes a warm render skips (the scene did not change): the first render's.
      for (const StageTime& s : first)
        if (!passes.count(s.name))
          std::printf("| %s | %d^2 | %s | %s (first render only) | %.2f | |\n", to_string(m), size,
                      name.c_str(), s.name.c_str(), s.ms);
      std::printf("| %s | %d^2 | %s | **total (stages)** | %.2f | |\n", to_string(m), size,
                  name.c_str(), median(total));
      std::printf("| %s | %d^2 | %s | **wall, whole render() call** | %.2f | |\n", to_string(m),
                  size, name.c_str(), median(wall));
      std::fflush(stdout);
    }
  return 0;
}
