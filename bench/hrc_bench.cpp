// Holographic radiance cascades on the CPU, measured as seed 004's Table 1: time against grid
// size split into merge up (T_0..T_N, tracing included) and merge down (R), with a warm
// workspace as a renderer would keep it; scene independence (2 to 1002 lights); storage.
#include <benchmark/benchmark.h>

#include <string>

#include "bench_scenes.hpp"
#include "flatland/hrc/hrc.hpp"
#include "flatland/medium.hpp"
#include "penumbra/flatland/render.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::flatland;

// Solves repeatedly on one workspace (the first, untimed solve allocates and touches it) and
// reports the paper's split.
void run_warm(benchmark::State& state, const Scene& scene, const HrcOptions& o) {
  const Medium medium = make_medium(scene);
  hrc::Workspace workspace;
  std::vector<float> fluence;
  std::vector<StageTime> stages;
  hrc::solve(medium, scene.environment, o, workspace, fluence, stages);
  double up = 0, down = 0, other = 0, gather = 0, fan = 0;
  for (auto _ : state) {
    stages.clear();
    hrc::solve(medium, scene.environment, o, workspace, fluence, stages);
    for (const StageTime& s : stages) {
      if (s.name == "trace T0-T2" || s.name == "merge up T3-TN")
        up += s.ms;
      else if (s.name == "gather")
        gather += s.ms;
      else if (s.name == "merge down R")
        down += s.ms;
      else if (s.name == "fan")
        fan += s.ms;
      else
        other += s.ms;
    }
    benchmark::DoNotOptimize(fluence.data());
  }
  const double n = double(state.iterations());
  state.counters["merge_up_ms"] = up / n;
  state.counters["merge_down_ms"] = down / n;
  state.counters["views_ms"] = other / n;  // the world, the views, a whole-fluence blur
  state.counters["gather_ms"] = gather / n;
  state.counters["fan_ms"] = fan / n;  // HrcOptions::wall_fan and near_fan
  state.counters["memory_MiB"] =
      double(hrc::working_bytes(scene.width, scene.height, o)) / (1 << 20);
  // T and two layers of R alone, and the seed's formula for them at the next power of two.
  state.counters["structure_MiB"] =
      double(hrc::structure_bytes(scene.width, scene.height, o.storage)) / (1 << 20);
  state.counters["paper_MiB"] = double(hrc::paper_bytes(scene.width, scene.height, o)) / (1 << 20);
  state.counters["cells/s"] =
      benchmark::Counter(double(scene.cells()) * n, benchmark::Counter::kIsRate);
}

// Table 1's sizes, on the 102-light scene scaled to the grid.
void BM_HrcGrid(benchmark::State& state) {
  const Scene scene = *build_scene(bench::lights_scene(int(state.range(0)), 102));
  run_warm(state, scene, {});
}
BENCHMARK(BM_HrcGrid)
    ->Arg(256)
    ->Arg(512)
    ->Arg(1024)
    ->Arg(2048)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Same grid and walls, 2 to 1002 lights: HRC does not branch on the scene.
void BM_HrcLights512(benchmark::State& state) {
  const Scene scene = *build_scene(bench::lights_scene(512, int(state.range(0))));
  run_warm(state, scene, {});
}
BENCHMARK(BM_HrcLights512)
    ->Arg(2)
    ->Arg(102)
    ->Arg(1002)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The fan's cost against its reach: 102 and 1002 lights at 512^2, wall_fan M and near_fan K
// (docs/PERFORMANCE.md: why `--wall-fan 4 --near-fan 8` is not the default).
void BM_HrcFan512(benchmark::State& state) {
  const Scene scene = *build_scene(bench::lights_scene(512, int(state.range(0))));
  HrcOptions o;
  o.wall_fan = int(state.range(1));
  o.near_fan = int(state.range(2));
  run_warm(state, scene, o);
}
BENCHMARK(BM_HrcFan512)
    ->ArgsProduct({{102, 1002}, {3, 4}, {2, 8}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Half-precision storage of T and R against single precision, at two sizes (how each scales).
void BM_HrcStorage(benchmark::State& state) {
  const Scene scene = *build_scene(bench::lights_scene(int(state.range(0)), 102));
  HrcOptions o;
  o.storage = Storage(state.range(1));
  state.SetLabel(to_string(o.storage));
  run_warm(state, scene, o);
}
BENCHMARK(BM_HrcStorage)
    ->ArgsProduct({{512, 1024}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// One render() from nothing, as the command line runs it: allocation and first touch of every
// buffer included.
void BM_HrcRenderCold512(benchmark::State& state) {
  const Scene scene = *build_scene(bench::lights_scene(512, 102));
  RenderOptions o;
  o.method = Method::hrc;
  for (auto _ : state) {
    Expected<RenderResult> r = render(scene, o);
    benchmark::DoNotOptimize(r->fluence.data());
  }
}
BENCHMARK(BM_HrcRenderCold512)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
