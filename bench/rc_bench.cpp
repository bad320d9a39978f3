// Radiance cascades on the CPU: time against grid size, and the paper's scene-independence
// claim (seed 001, section 4.1: 2, 102 and 1002 lights take the same time).
#include <benchmark/benchmark.h>

#include "bench_run.hpp"
#include "bench_scenes.hpp"
#include "penumbra/flatland/render.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::flatland;
using bench::build;
using bench::run;

// Grid size: a fixed layout of walls and 102 lights scaled to the grid.
void BM_RcGrid(benchmark::State& state) {
  const Scene scene = build(bench::lights_scene(int(state.range(0)), 102));
  run(state, scene, {});
}
BENCHMARK(BM_RcGrid)->Arg(256)->Arg(512)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

// Same grid and walls, different numbers of lights: the time should not change.
void BM_RcLights512(benchmark::State& state) {
  const Scene scene = build(bench::lights_scene(512, int(state.range(0))));
  run(state, scene, {});
}
BENCHMARK(BM_RcLights512)
    ->Arg(2)
    ->Arg(102)
    ->Arg(1002)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Merge options at 512^2 (the fix costs a trace per upper probe and child ray).
void BM_RcMerge512(benchmark::State& state) {
  const Scene scene = build(bench::lights_scene(512, 102));
  RenderOptions o;
  o.rc.fix = MergeFix(state.range(0));
  state.SetLabel(to_string(o.rc.fix));
  run(state, scene, o);
}
BENCHMARK(BM_RcMerge512)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime();

// Interval extension (seed 001 eq. 16) against tracing whole intervals, vanilla merging; and the
// distance field against plain cell stepping, with the default options.
void BM_RcVariants512(benchmark::State& state) {
  const Scene scene = build(bench::lights_scene(512, 102));
  RenderOptions o;
  switch (state.range(0)) {
    case 0:
      o.rc.fix = MergeFix::none;
      state.SetLabel("vanilla");
      break;
    case 1:
      o.rc.fix = MergeFix::none;
      o.rc.extend = true;
      state.SetLabel("vanilla + extend");
      break;
    case 2:
      o.rc.preaverage = true;
      state.SetLabel("bilinear fix + preaverage");
      break;
    case 3:
      o.distance_field = false;
      state.SetLabel("bilinear fix, no distance field");
      break;
  }
  run(state, scene, o);
}
BENCHMARK(BM_RcVariants512)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
