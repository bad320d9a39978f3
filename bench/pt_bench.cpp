// The reference path tracer: ways of skipping empty space (plain DDA, 8x8 blocks, distance-field
// jumps, both), next event estimation, and bounces.
#include <benchmark/benchmark.h>

#include "bench_run.hpp"
#include "bench_scenes.hpp"

namespace {

using namespace penumbra;

// Traversal: 0 plain DDA, 1 blocks, 2 distance field, 3 both; for the path tracer (long rays to
// the border) and the cascades (short intervals), on the 102-light scene at 512^2.
void BM_Traversal512(benchmark::State& state) {
  static const Scene scene = bench::build(bench::lights_scene(512, 102));
  RenderOptions o;
  o.method = state.range(0) == 0 ? Method::pt : Method::rc;
  o.pt.spp = 4;
  o.blocks = state.range(1) & 1;
  o.distance_field = state.range(1) & 2;
  static const char* names[] = {"plain DDA", "blocks", "distance field", "blocks + distance"};
  state.SetLabel(std::string(to_string(o.method)) + ", " + names[state.range(1)]);
  bench::run(state, scene, o);
}
BENCHMARK(BM_Traversal512)
    ->ArgsProduct({{0, 1}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Sampling: plain, NEE, and 4 bounces (a ray per bounce), 4 samples per cell.
void BM_PtSampling512(benchmark::State& state) {
  static const Scene scene = bench::build(bench::lights_scene(512, 102));
  RenderOptions o;
  o.method = Method::pt;
  o.pt.spp = 4;
  o.pt.nee = state.range(0) >= 1;
  o.bounces = state.range(0) == 2 ? 4 : 1;
  static const char* names[] = {"plain", "nee", "nee, 4 bounces"};
  state.SetLabel(names[state.range(0)]);
  bench::run(state, scene, o);
}
BENCHMARK(BM_PtSampling512)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
