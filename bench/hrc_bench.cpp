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
  double up = 0, down = 0, other = 0, gather = 0, fan = 0, work = 0;
  for (auto _ : state) {
    stages.clear();
    hrc::solve(medium, scene.environment, o, workspace, fluence, stages);
    for (const StageTime& s : stages) {
      work += double(s.work);
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
  state.counters["fan_ms"] = fan / n;  // HrcOptions::wall_fan, fan_share and near_fan
  // The values the stages computed (StageTime::work), the same on every scene of a grid size.
  state.counters["work_M"] = work / n / 1e6;
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

// Same grid, 2 to 1002 lights among the same walls, fog everywhere, or nothing but the
// environment: HRC's work does not depend on the scene (the fan gathers the same number of
// cells on each).
void BM_HrcScenes512(benchmark::State& state) {
  const int which = int(state.range(0));
  SceneDesc d = bench::lights_scene(512, which == 0 ? 2 : which == 1 ? 102 : 1002);
  if (which == 3) {  // the 102 lights in a glowing fog over the whole grid
    d = bench::lights_scene(512, 102);
    d.shapes.insert(d.shapes.begin(),
                    {Box{{256, 256}, {512, 512}, 0}, Material{{0.02f, 0.02f, 0.03f}, 0.05f, {}}});
  } else if (which == 4) {
    d.shapes.clear();
  }
  const char* names[] = {"2 lights", "102 lights", "1002 lights", "fog, 102 lights", "nothing"};
  state.SetLabel(names[which]);
  run_warm(state, *build_scene(d), {});
}
BENCHMARK(BM_HrcScenes512)->DenseRange(0, 4)->Unit(benchmark::kMillisecond)->UseRealTime();

// The fan's cost against its reach: 102 and 1002 lights at 512^2, wall_fan M and fan_share
// S / 1024 (docs/PERFORMANCE.md).
void BM_HrcFan512(benchmark::State& state) {
  const Scene scene = *build_scene(bench::lights_scene(512, int(state.range(0))));
  HrcOptions o;
  o.wall_fan = int(state.range(1));
  o.fan_share = float(state.range(2)) / 1024;
  run_warm(state, scene, o);
}
BENCHMARK(BM_HrcFan512)
    ->ArgsProduct({{102, 1002}, {3, 4}, {16, 64}})
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
