// The 3D methods on the example scenes: the path tracer's samples and rays per second, and
// SPWI's and the screen-space cascades' time and rays per second, on one thread and on all, so
// that a change to a method or to the ray queries shows in both; ssrc and SPWI on the same
// 1920x1080 frame (issue 38's aim), and ssrc with 2 or 200 of 200 spheres emitting (its cost
// does not depend on the lights).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::spaceland;

struct Example {
  const char* name;
  int bounces;
};
// The Cornell box (42 triangles, a small light), the bunny under sky and sun (70k triangles),
// and the textured glTF box (the sun, a texture lookup per hit).
const Example kExamples[] = {{"cornell", 4}, {"bunny_sky", 2}, {"gltf_box", 2}};

Scene load(int which) {
  const std::string path =
      std::string(PENUMBRA_SCENES_DIR) + "/3d/" + kExamples[which].name + ".json";
  Expected<Scene> loaded = load_scene(path);
  if (!loaded) {
    std::fprintf(stderr, "%s\n", loaded.error().message.c_str());
    std::exit(1);
  }
  return std::move(*loaded);
}

const Scene& example(int which) {
  static const Scene scenes[3] = {load(0), load(1), load(2)};
  return scenes[which];
}

// Renders `scene` with `o` once per iteration; reports rays/s and, for a progressive method,
// samples/s (per pixel, summed over pixels).
void run(benchmark::State& state, const Scene& scene, const RenderOptions& o,
         const std::string& label) {
  std::uint64_t rays = 0, samples = 0;
  for (auto _ : state) {
    Expected<RenderResult> r = render(scene, o);
    if (!r) {
      state.SkipWithError(r.error().message.c_str());
      return;
    }
    rays += r->rays;
    samples += r->samples * std::uint64_t(scene.camera.width) * scene.camera.height;
    benchmark::DoNotOptimize(r->radiance.data());
  }
  state.SetLabel(label + (o.threads == 1 ? ", 1 thread" : ", all threads"));
  state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
  if (samples > 0)
    state.counters["samples/s"] = benchmark::Counter(double(samples), benchmark::Counter::kIsRate);
}

// The path tracer at 4 samples per pixel. Args: example, threads (0: all).
void BM_Pt3d(benchmark::State& state) {
  const Example& e = kExamples[state.range(0)];
  RenderOptions o;
  o.pt.spp = 4;
  o.bounces = e.bounces;
  o.threads = int(state.range(1));
  run(state, example(int(state.range(0))), o,
      std::string(e.name) + ", " + std::to_string(e.bounces) + " bounces");
}
BENCHMARK(BM_Pt3d)->ArgsProduct({{0, 1, 2}, {1, 0}})->Unit(benchmark::kMillisecond)->UseRealTime();

// SPWI at its defaults. Args: example, threads (0: all).
void BM_Spwi3d(benchmark::State& state) {
  RenderOptions o;
  o.method = Method::spwi;
  o.threads = int(state.range(1));
  run(state, example(int(state.range(0))), o, kExamples[state.range(0)].name);
}
BENCHMARK(BM_Spwi3d)
    ->ArgsProduct({{0, 1, 2}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The screen-space cascades at their defaults. Args: example, threads (0: all).
void BM_Ssrc3d(benchmark::State& state) {
  RenderOptions o;
  o.method = Method::ssrc;
  o.threads = int(state.range(1));
  run(state, example(int(state.range(0))), o, kExamples[state.range(0)].name);
}
BENCHMARK(BM_Ssrc3d)
    ->ArgsProduct({{0, 1, 2}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The Cornell box at 1920x1080 on all threads, by ssrc (arg 0) and SPWI (arg 1): one frame each.
void BM_FullHd3d(benchmark::State& state) {
  Scene s = example(0);
  s.camera.width = 1920;
  s.camera.height = 1080;
  RenderOptions o;
  o.method = state.range(0) == 0 ? Method::ssrc : Method::spwi;
  run(state, s, o, std::string("cornell 1920x1080, ") + to_string(o.method));
}
BENCHMARK(BM_FullHd3d)->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// 200 spheres of radius 0.1 on a floor seen from above, `emitting` of them lights (the rest
// grey): the screen-space cascades' time must not depend on it. Arg: emitting (2 or 200).
Scene spheres(int emitting) {
  Scene s;
  s.camera.position = {0, 8, 4};
  s.camera.look_at = {0, 0, 0};
  s.camera.width = 640;
  s.camera.height = 360;
  Material grey, light;
  grey.name = "grey";
  grey.albedo = {0.5f, 0.5f, 0.5f};
  light.name = "light";
  light.emission = {4, 3, 2};
  s.materials = {grey, light};
  Disk floor;
  floor.radius = 20;
  floor.material = 0;
  floor.object = 0;
  s.disks.push_back(floor);
  s.objects.push_back("objects[0] (disk)");
  for (int k = 0; k < 200; ++k) {
    Sphere b;
    b.center = {float(k % 20) * 0.5f - 4.75f, 0.1f, float(k / 20) * 0.5f - 2.25f};
    b.radius = 0.1f;
    b.material = k % (200 / emitting) == 0 ? 1 : 0;
    b.object = int(s.objects.size());
    s.objects.push_back("objects[" + std::to_string(s.objects.size()) + "] (sphere)");
    s.spheres.push_back(b);
  }
  return s;
}
void BM_Ssrc3dLights(benchmark::State& state) {
  const Scene s = spheres(int(state.range(0)));
  RenderOptions o;
  o.method = Method::ssrc;
  run(state, s, o, std::to_string(state.range(0)) + " of 200 spheres emitting");
}
BENCHMARK(BM_Ssrc3dLights)->Arg(2)->Arg(200)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
