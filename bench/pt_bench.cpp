// The reference path tracer: ways of skipping empty space (plain DDA, 8x8 blocks, distance-field
// jumps, both) on three kinds of scene, next event estimation, and bounces.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench_run.hpp"
#include "bench_scenes.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::flatland;

// An example scene from scenes/ (the source tree's, so the benchmark runs from anywhere).
Scene example(const char* name) {
  const std::string path = std::string(PENUMBRA_SCENES_DIR) + "/" + name + ".json";
  Expected<SceneDesc> d = load_scene(path);
  if (!d) {
    std::fprintf(stderr, "%s\n", d.error().message.c_str());
    std::exit(1);
  }
  return bench::build(*d);
}

const Scene& scene(int which) {
  static const Scene lights = bench::build(bench::lights_scene(512, 102));
  static const Scene occluder = example("occluder");
  static const Scene cornell = example("cornell");
  const Scene* scenes[] = {&lights, &occluder, &cornell};
  return *scenes[which];
}
const char* scene_names[] = {"102 lights", "occluder", "cornell"};

void set_traversal(RenderOptions& o, int traversal) {
  o.blocks = traversal & 1;
  o.distance_field = traversal & 2;
}
const char* traversal_names[] = {"plain DDA", "blocks", "distance field", "blocks + distance"};

// Traversal: 0 plain DDA, 1 blocks, 2 distance field, 3 both (the default). The path tracer's
// rays run to the border or the first opaque cell, 4 samples per cell, on three 512^2 scenes:
// scattered small lights, one light and one box in empty space, a closed box with fog.
void BM_PtTraversal512(benchmark::State& state) {
  RenderOptions o;
  o.method = Method::pt;
  o.pt.spp = 4;
  set_traversal(o, int(state.range(1)));
  state.SetLabel(std::string(scene_names[state.range(0)]) + ", " + traversal_names[state.range(1)]);
  bench::run(state, scene(int(state.range(0))), o);
}
BENCHMARK(BM_PtTraversal512)
    ->ArgsProduct({{0, 1, 2}, {0, 1, 2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The same for the cascades (short intervals and connections), default options, 102 lights.
void BM_RcTraversal512(benchmark::State& state) {
  RenderOptions o;
  set_traversal(o, int(state.range(0)));
  state.SetLabel(traversal_names[state.range(0)]);
  bench::run(state, scene(0), o);
}
BENCHMARK(BM_RcTraversal512)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseRealTime();

// Sampling on the Cornell box (reflecting walls, so bounces cost): plain, NEE, and NEE with 2
// and 4 bounces (a ray per bounce and level), 4 samples per cell.
void BM_PtSampling512(benchmark::State& state) {
  RenderOptions o;
  o.method = Method::pt;
  o.pt.spp = 4;
  o.pt.nee = state.range(0) >= 1;
  o.bounces = state.range(0) == 2 ? 2 : state.range(0) == 3 ? 4 : 1;
  static const char* names[] = {"plain", "nee", "nee, 2 bounces", "nee, 4 bounces"};
  state.SetLabel(names[state.range(0)]);
  bench::run(state, scene(2), o);
}
BENCHMARK(BM_PtSampling512)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
