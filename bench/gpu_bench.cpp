// The GPU kernels against their CPU references, on the device the machine has (lavapipe, Mesa's
// CPU Vulkan driver, where there is no GPU: then both run on the same cores). The GPU figure is
// the whole call (upload, dispatches, download); the counter gpu_ms is the dispatches alone,
// from timestamp queries.
#include <benchmark/benchmark.h>

#include <memory>

#include "bench_scenes.hpp"
#include "flatland/gpu/distance.hpp"
#include "flatland/medium.hpp"
#include "penumbra/flatland/render.hpp"
#include "penumbra/flatland/scene.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::flatland;

Medium lights_medium(int size) {
  return make_medium(*build_scene(bench::lights_scene(size, 102)));
}

void BM_JumpFloodCpu(benchmark::State& state) {
  const Medium m = lights_medium(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(jump_flood_distance(m).data());
}
BENCHMARK(BM_JumpFloodCpu)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_JumpFloodGpu(benchmark::State& state) {
  static Expected<std::shared_ptr<penumbra::gpu::Context>> context =
      penumbra::gpu::Context::create(true);
  if (!context) {
    state.SkipWithError(context.error().message.c_str());
    return;
  }
  state.SetLabel((*context)->info().name);
  const Medium m = lights_medium(int(state.range(0)));
  double gpu_ms = 0;
  for (auto _ : state) {
    std::vector<std::pair<std::string, double>> passes;
    Expected<std::vector<float>> d = flatland::gpu::jump_flood_distance(**context, m, &passes);
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

// A whole render on the GPU (one bounce; HRC f32, RC at its defaults) through a Renderer, so
// kernels, scene and buffers stay on the device between iterations as in the painter: gpu_ms
// is the passes' GPU time, the wall figure adds the host's share (submission, read back).
void render_gpu(benchmark::State& state, Method method) {
  static Expected<std::shared_ptr<penumbra::gpu::Context>> context =
      penumbra::gpu::Context::create(true);
  if (!context) {
    state.SkipWithError(context.error().message.c_str());
    return;
  }
  state.SetLabel((*context)->info().name);
  const Scene scene = *build_scene(bench::lights_scene(int(state.range(0)), 102));
  RenderOptions o;
  o.method = method;
  o.device = Device::gpu;
  Renderer renderer;
  double gpu_ms = 0;
  for (auto _ : state) {
    Expected<RenderResult> r = renderer.render(scene, o);
    if (!r) {
      state.SkipWithError(r.error().message.c_str());
      return;
    }
    benchmark::DoNotOptimize(r->fluence.data());
    for (const StageTime& p : r->stages)
      if (p.name != "setup and transfers") gpu_ms += p.ms;
  }
  state.counters["gpu_ms"] = gpu_ms / double(state.iterations());
}
void BM_HrcGpu(benchmark::State& state) {
  render_gpu(state, Method::hrc);
}
BENCHMARK(BM_HrcGpu)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();
void BM_RcGpu(benchmark::State& state) {
  render_gpu(state, Method::rc);
}
BENCHMARK(BM_RcGpu)->Arg(256)->Arg(512)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
