// Running a method under Google Benchmark with the counters every benchmark reports.
#pragma once

#include <benchmark/benchmark.h>

#include "penumbra/flatland/render.hpp"

namespace penumbra::bench {

using namespace penumbra::flatland;

// Times render() (its own computation time, not scene building) and reports cells/s, working
// memory, intervals (rays for the path tracer) per second and the mean computation time.
inline void run(benchmark::State& state, const Scene& scene, const RenderOptions& options) {
  double ms = 0;
  std::uint64_t memory = 0, intervals = 0;
  for (auto _ : state) {
    Expected<RenderResult> r = render(scene, options);
    if (!r) {
      state.SkipWithError(r.error().message.c_str());
      return;
    }
    ms += r->time_ms;
    memory = r->memory_bytes;
    intervals = r->intervals;
    benchmark::DoNotOptimize(r->fluence.data());
  }
  state.counters["cells/s"] =
      benchmark::Counter(double(scene.cells()) * state.iterations(), benchmark::Counter::kIsRate);
  state.counters["memory_MiB"] = double(memory) / (1 << 20);
  state.counters["Mintervals/s"] = double(intervals) / (ms / double(state.iterations())) / 1e3;
  state.counters["compute_ms"] = ms / double(state.iterations());
}

inline Scene build(const SceneDesc& d) {
  return *build_scene(d);
}

}  // namespace penumbra::bench
