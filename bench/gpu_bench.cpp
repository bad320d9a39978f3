// The GPU kernels against their CPU references, on the device the machine has (lavapipe, Mesa's
// CPU Vulkan driver, where there is no GPU: then both run on the same cores). The GPU figure is
// the whole call (upload, dispatches, download); the counter gpu_ms is the dispatches alone,
// from timestamp queries.
#include <benchmark/benchmark.h>

#include <memory>

#include "bench_scenes.hpp"
#include "flatland/medium.hpp"
#include "gpu/distance.hpp"
#include "gpu/hrc.hpp"
#include "penumbra/scene.hpp"

namespace {

using namespace penumbra;

Medium lights_medium(int size) {
  return make_medium(*build_scene(bench::lights_scene(size, 102)));
}

void BM_JumpFloodCpu(benchmark::State& state) {
  const Medium m = lights_medium(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(jump_flood_distance(m).data());
}
BENCHMARK(BM_JumpFloodCpu)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_JumpFloodGpu(benchmark::State& state) {
  static Expected<std::shared_ptr<gpu::Context>> context = gpu::Context::create(true);
  if (!context) {
    state.SkipWithError(context.error().message.c_str());
    return;
  }
  state.SetLabel((*context)->info().name);
  const Medium m = lights_medium(int(state.range(0)));
  double gpu_ms = 0;
  for (auto _ : state) {
    std::vector<std::pair<std::string, double>> passes;
    Expected<std::vector<float>> d = gpu::jump_flood_distance(**context, m, &passes);
    if (!d) {
      state.SkipWithError(d.error().message.c_str());
      return;
    }
    benchmark::DoNotOptimize(d->data());
    for (const auto& p : passes) gpu_ms += p.second;
  }
  state.counters["gpu_ms"] = gpu_ms / double(state.iterations());
}
BENCHMARK(BM_JumpFloodGpu)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

// A whole HRC solve (one bounce, f32): gpu_ms is the dispatches; the whole call also builds the
// pipelines and buffers, which a renderer kept between frames will not.
void BM_HrcGpu(benchmark::State& state) {
  static Expected<std::shared_ptr<gpu::Context>> context = gpu::Context::create(true);
  if (!context) {
    state.SkipWithError(context.error().message.c_str());
    return;
  }
  state.SetLabel((*context)->info().name);
  const Scene scene = *build_scene(bench::lights_scene(int(state.range(0)), 102));
  const Medium m = make_medium(scene);
  double gpu_ms = 0;
  for (auto _ : state) {
    std::vector<StageTime> passes;
    Expected<std::vector<float>> f = gpu::hrc_solve(**context, m, scene.environment, {}, &passes);
    if (!f) {
      state.SkipWithError(f.error().message.c_str());
      return;
    }
    benchmark::DoNotOptimize(f->data());
    for (const StageTime& p : passes)
      if (p.name != "setup and transfers") gpu_ms += p.ms;
  }
  state.counters["gpu_ms"] = gpu_ms / double(state.iterations());
}
BENCHMARK(BM_HrcGpu)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
