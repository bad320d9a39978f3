// RayScene (Embree 3) throughput: rays per second for coherent primary rays, shadow rays towards
// a light and incoherent secondary rays, on the Stanford bunny in a box, on many spheres and on
// the Cornell box example scene; the build time and the bytes per triangle
// RayScene::estimate_bytes is set from.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "io/json_reader.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/camera.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/scene/mesh_file.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::spaceland;

// The synthetic scenes' camera: 512 x 512 looking into the box.
Camera box_camera() {
  Camera cam;
  cam.position = {0, 0, 3.6f};
  cam.look_at = {0, 0, 0};
  cam.fov_y = 40.1f;
  cam.width = cam.height = 512;
  return cam;
}

TriangleMesh quad(Vec3 corner, Vec3 u, Vec3 v) {
  TriangleMesh m;
  m.positions = {corner, corner + u, corner + u + v, corner + v};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.materials = {0, 0};
  return m;
}

// The box [-1, 1]^3 open towards +z (the camera), a light quad under its ceiling.
void add_box(Scene& s) {
  s.meshes.push_back(quad({-1, -1, -1}, {2, 0, 0}, {0, 0, 2}));
  s.meshes.push_back(quad({-1, 1, -1}, {2, 0, 0}, {0, 0, 2}));
  s.meshes.push_back(quad({-1, -1, -1}, {0, 2, 0}, {0, 0, 2}));
  s.meshes.push_back(quad({1, -1, -1}, {0, 2, 0}, {0, 0, 2}));
  s.meshes.push_back(quad({-1, -1, -1}, {2, 0, 0}, {0, 2, 0}));
  s.meshes.push_back(quad({-0.25f, 0.99f, -0.25f}, {0.5f, 0, 0}, {0, 0, 0.5f}));
}

// The glmark2 bunny (read by the scene's own OBJ reader), scaled into the box, on its floor.
bool add_bunny(Scene& s) {
  MeshFile file;
  try {
    file = read_mesh_file("/usr/share/glmark2/models/bunny.obj", "rays_bench", "bunny",
                          std::uint64_t(1) << 30);
  } catch (const io::JsonFailure&) {
    return false;
  }
  TriangleMesh m = std::move(file.mesh);
  Vec3 lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
  for (Vec3 p : m.positions) lo = min(lo, p), hi = max(hi, p);
  const float k = 1.6f / std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  const Vec3 c = (lo + hi) * 0.5f;
  for (Vec3& p : m.positions) p = (p - c) * k + Vec3{0, -1 - (lo.y - c.y) * k, 0};
  m.materials.assign(m.triangles.size(), 0);
  s.meshes.push_back(std::move(m));
  return true;
}

Scene bunny_scene() {
  Scene s;
  s.camera = box_camera();
  add_box(s);
  add_bunny(s);
  return s;
}

// 10,000 small spheres in the box.
Scene spheres_scene() {
  Scene s;
  s.camera = box_camera();
  add_box(s);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-0.9f, 0.9f);
  for (int i = 0; i < 10000; ++i) s.spheres.push_back({{u(rng), u(rng), u(rng)}, 0.02f});
  return s;
}

// The Cornell box of scenes/3d, its camera at 512 x 512.
Scene cornell_scene() {
  Expected<Scene> s = load_scene(std::string(PENUMBRA_SCENES_DIR) + "/3d/cornell.json");
  if (!s) {
    std::fprintf(stderr, "%s\n", s.error().message.c_str());
    std::exit(1);
  }
  s->camera.width = s->camera.height = 512;
  return std::move(*s);
}

// A scene, its light (the rectangle corner + a u + b v that shadow rays aim at) and its label.
struct Bench {
  Scene scene;
  Vec3 light_corner, light_u, light_v;
  const char* label;
};

const Bench& bench(int which) {
  static const Bench benches[] = {
      {bunny_scene(), {-0.25f, 0.99f, -0.25f}, {0.5f, 0, 0}, {0, 0, 0.5f}, "bunny in a box"},
      {spheres_scene(),
       {-0.25f, 0.99f, -0.25f},
       {0.5f, 0, 0},
       {0, 0, 0.5f},
       "10k spheres in a box"},
      {cornell_scene(), {213, 548.8f, 227}, {130, 0, 0}, {0, 0, 105}, "Cornell box (example)"}};
  return benches[which];
}

const Scene& scene(int which) {
  return bench(which).scene;
}

const RayScene& ray_scene(int which) {
  static const RayScene scenes[] = {std::move(RayScene::build(scene(0))).value(),
                                    std::move(RayScene::build(scene(1))).value(),
                                    std::move(RayScene::build(scene(2))).value()};
  return scenes[which];
}

// Every pixel's camera ray, rows in order (coherent).
std::vector<Ray> primary_rays(int which) {
  const Camera& cam = scene(which).camera;
  const CameraRays camera(cam);
  std::vector<Ray> rays;
  for (int j = 0; j < cam.height; ++j)
    for (int i = 0; i < cam.width; ++i) rays.push_back(camera.ray(i, j));
  return rays;
}

struct Points {
  std::vector<Vec3> p, n;
};

// Where the primary rays land.
Points first_hits(int which) {
  const RayScene& rs = ray_scene(which);
  Points pts;
  for (const Ray& r : primary_rays(which)) {
    Hit h;
    if (!rs.intersect(r, h)) continue;
    pts.p.push_back(h.position);
    pts.n.push_back(h.geometric_normal);
  }
  return pts;
}

void label(benchmark::State& state, int which) {
  state.SetLabel(bench(which).label);
}

template <class F>
void run(benchmark::State& state, std::size_t rays_per_iteration, F&& body) {
  for (auto _ : state) body();
  state.SetItemsProcessed(std::int64_t(state.iterations() * rays_per_iteration));
}

void BM_RaysPrimary(benchmark::State& state) {
  const RayScene& rs = ray_scene(int(state.range(0)));
  const std::vector<Ray> rays = primary_rays(int(state.range(0)));
  label(state, int(state.range(0)));
  run(state, rays.size(), [&] {
    Hit h;
    for (const Ray& r : rays) benchmark::DoNotOptimize(rs.intersect(r, h));
  });
}
BENCHMARK(BM_RaysPrimary)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The same rays through the span interface.
void BM_RaysPrimaryStream(benchmark::State& state) {
  const RayScene& rs = ray_scene(int(state.range(0)));
  const std::vector<Ray> rays = primary_rays(int(state.range(0)));
  std::vector<Hit> hits(rays.size());
  std::vector<std::uint8_t> found(rays.size());
  label(state, int(state.range(0)));
  run(state, rays.size(), [&] {
    rs.intersect(rays, hits, found, true);
    benchmark::DoNotOptimize(found.data());
  });
}
BENCHMARK(BM_RaysPrimaryStream)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

std::vector<Ray> shadow_rays(int which) {
  const RayScene& rs = ray_scene(which);
  const Bench& b = bench(which);
  const Points pts = first_hits(which);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<Ray> rays;
  for (std::size_t i = 0; i < pts.p.size(); ++i) {
    const Vec3 target = b.light_corner + b.light_u * u(rng) + b.light_v * u(rng);
    rays.push_back(rs.shadow_ray(pts.p[i], pts.n[i], target, {0, -1, 0}));
  }
  return rays;
}

// From every first hit to a random point on the light.
void BM_RaysShadow(benchmark::State& state) {
  const RayScene& rs = ray_scene(int(state.range(0)));
  const std::vector<Ray> rays = shadow_rays(int(state.range(0)));
  label(state, int(state.range(0)));
  run(state, rays.size(), [&] {
    for (const Ray& r : rays) benchmark::DoNotOptimize(rs.occluded(r));
  });
}
BENCHMARK(BM_RaysShadow)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// From every first hit in a uniformly random direction of its side (incoherent).
std::vector<Ray> secondary_rays(int which) {
  const RayScene& rs = ray_scene(which);
  const Points pts = first_hits(which);
  std::mt19937 rng(3);
  std::normal_distribution<float> g;
  std::vector<Ray> rays;
  for (std::size_t i = 0; i < pts.p.size(); ++i) {
    Vec3 d = normalize(Vec3{g(rng), g(rng), g(rng)});
    const Vec3 to_camera = scene(which).camera.position - pts.p[i];
    if (dot(d, pts.n[i]) * dot(pts.n[i], to_camera) < 0) d = -d;  // on the camera's side
    rays.push_back({rs.spawn(pts.p[i], pts.n[i], d), d});
  }
  return rays;
}

void BM_RaysSecondary(benchmark::State& state) {
  const RayScene& rs = ray_scene(int(state.range(0)));
  const std::vector<Ray> rays = secondary_rays(int(state.range(0)));
  label(state, int(state.range(0)));
  run(state, rays.size(), [&] {
    Hit h;
    for (const Ray& r : rays) benchmark::DoNotOptimize(rs.intersect(r, h));
  });
}
BENCHMARK(BM_RaysSecondary)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RaysSecondaryStream(benchmark::State& state) {
  const RayScene& rs = ray_scene(int(state.range(0)));
  const std::vector<Ray> rays = secondary_rays(int(state.range(0)));
  std::vector<Hit> hits(rays.size());
  std::vector<std::uint8_t> found(rays.size());
  label(state, int(state.range(0)));
  run(state, rays.size(), [&] {
    rs.intersect(rays, hits, found, true);  // the stream path, to show it loses here
    benchmark::DoNotOptimize(found.data());
  });
}
BENCHMARK(BM_RaysSecondaryStream)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Building the BVH; the counter is Embree's bytes per triangle or sphere, the measured constant
// behind RayScene::estimate_bytes.
void BM_RaysBuild(benchmark::State& state) {
  const Scene& s = scene(int(state.range(0)));
  std::uint64_t bytes = 0;
  for (auto _ : state) {
    Expected<RayScene> r = RayScene::build(s);
    if (!r) {
      state.SkipWithError(r.error().message.c_str());
      return;
    }
    bytes = r->bytes();
  }
  std::uint64_t prims = s.spheres.size();
  for (const TriangleMesh& m : s.meshes) prims += m.triangles.size();
  label(state, int(state.range(0)));
  state.counters["bytes/prim"] = double(bytes) / double(prims);
  state.counters["estimate/bytes"] = double(RayScene::estimate_bytes(s)) / double(bytes);
}
BENCHMARK(BM_RaysBuild)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
