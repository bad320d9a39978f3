// The Vulkan layer on whatever device the machine has (Mesa's lavapipe in CI): device choice,
// buffers, kernels, batches and timestamps, against the CPU code as reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "flatland/gpu/distance.hpp"
#include "flatland/gpu/hrc.hpp"
#include "flatland/gpu/shaders.hpp"
#include "flatland/gpu/solver.hpp"
#include "flatland/hrc/hrc.hpp"
#include "flatland/medium.hpp"
#include "flatland/method.hpp"
#include "flatland/rc/cascade.hpp"
#include "gpu/vulkan.hpp"
#include "image_metrics.hpp"
#include "penumbra/flatland/render.hpp"
#include "penumbra/flatland/scene.hpp"
#include "test_support.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::flatland;
using penumbra::testing::relative_rmse;

// The plan render() would make, for calling the GPU solver directly (RC's directions filled).
Plan plan_of(int w, int h, const RenderOptions& o, bool fill = true) {
  Expected<Plan> p = make_plan(w, h, o);
  EXPECT_TRUE(p.ok()) << (p.ok() ? "" : p.error().message);
  if (!p.ok()) return {};
  if (fill) rc::fill_directions(p->cascades);
  return *p;
}

std::shared_ptr<penumbra::gpu::Context> context() {
  Expected<std::shared_ptr<penumbra::gpu::Context>> c = penumbra::gpu::Context::create(true);
  EXPECT_TRUE(c.ok()) << (c.ok() ? "" : c.error().message)
                      << " (scripts/install-deps.sh installs mesa-vulkan-drivers)";
  return c.ok() ? *c : nullptr;
}

TEST(Gpu, OpensADeviceAndNamesIt) {
  std::shared_ptr<penumbra::gpu::Context> c = context();
  ASSERT_TRUE(c);
  EXPECT_FALSE(c->info().name.empty());
  EXPECT_FALSE(c->info().type.empty());
  EXPECT_GT(c->info().max_workgroups_x, 0u);
  std::printf("device: %s (%s)\n", c->info().name.c_str(), c->info().type.c_str());
}

// The medium kernel against flatland's extinction(): every opacity class (clear, small values
// where log(1 - o) loses digits, ordinary, opaque).
TEST(Gpu, MediumKernelMatchesTheCpu) {
  std::shared_ptr<penumbra::gpu::Context> c = context();
  ASSERT_TRUE(c);
  std::vector<float> opacity = {0.0f, 1.0f, 1e-7f, 1e-4f, 0.01f, 0.0625f, 0.5f, 0.999f, 0.9999999f};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int i = 0; i < 100000; ++i) opacity.push_back(u(rng) * (i % 3 == 0 ? 0.05f : 1.0f));
  const std::uint32_t n = std::uint32_t(opacity.size());
  Expected<penumbra::gpu::Buffer> in = c->buffer(n * sizeof(float)),
                                  out = c->buffer(n * sizeof(float));
  ASSERT_TRUE(in.ok() && out.ok());
  std::copy(opacity.begin(), opacity.end(), in->as<float>());
  Expected<penumbra::gpu::Kernel> k =
      c->kernel("medium", flatland::gpu::shaders::medium(), 2, sizeof(std::uint32_t));
  ASSERT_TRUE(k.ok()) << k.error().message;
  Expected<penumbra::gpu::Batch> b = c->batch();
  ASSERT_TRUE(b.ok()) << b.error().message;
  penumbra::gpu::Buffer* buffers[] = {&*in, &*out};
  b->mark("medium");
  const penumbra::gpu::Groups g = penumbra::gpu::groups_1d(n, 256, c->info());
  b->dispatch(*k, buffers, &n, g.x, g.y);
  Expected<std::vector<std::pair<std::string, double>>> times = b->run();
  ASSERT_TRUE(times.ok()) << times.error().message;
  if (c->info().timestamp_period_ns > 0) {
    ASSERT_EQ(times->size(), 1u);
    EXPECT_EQ((*times)[0].first, "medium");
    EXPECT_GE((*times)[0].second, 0.0);
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    const float want = extinction(opacity[i]), got = out->as<float>()[i];
    if (std::isinf(want)) {
      ASSERT_TRUE(std::isinf(got)) << opacity[i];
      continue;
    }
    ASSERT_NEAR(got, want, 1e-5f * want + 1e-30f) << "opacity " << opacity[i];
  }
}

TEST(Gpu, MisuseIsAnErrorNotACrash) {
  std::shared_ptr<penumbra::gpu::Context> c = context();
  ASSERT_TRUE(c);
  Expected<penumbra::gpu::Kernel> k =
      c->kernel("medium", flatland::gpu::shaders::medium(), 2, sizeof(std::uint32_t));
  ASSERT_TRUE(k.ok()) << k.error().message;
  Expected<penumbra::gpu::Buffer> one = c->buffer(16);
  ASSERT_TRUE(one.ok());
  Expected<penumbra::gpu::Batch> b = c->batch();
  ASSERT_TRUE(b.ok());
  penumbra::gpu::Buffer* buffers[] = {&*one};
  const std::uint32_t n = 4;
  b->dispatch(*k, buffers, &n, 1);  // two buffers expected
  Expected<std::vector<std::pair<std::string, double>>> r = b->run();
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("takes 2 buffers"), std::string::npos) << r.error().message;
  // An absurd allocation is refused up front with a message.
  Expected<penumbra::gpu::Buffer> huge = c->buffer(std::size_t(1) << 50);
  ASSERT_FALSE(huge.ok());
  EXPECT_NE(huge.error().message.find("larger than"), std::string::npos) << huge.error().message;
  // Buffer ranges past the end, at a misaligned offset, or copies outside a buffer: errors.
  Expected<penumbra::gpu::Buffer> two = c->buffer(64);
  ASSERT_TRUE(two.ok());
  const std::size_t align = c->info().offset_alignment;
  for (const penumbra::gpu::Batch::Range bad :
       {penumbra::gpu::Batch::Range{&*two, 0, 128}, penumbra::gpu::Batch::Range{&*two, 64, 0},
        penumbra::gpu::Batch::Range{&*two, align > 1 ? align / 2 : 64, 4}}) {
    Expected<penumbra::gpu::Batch> rb = c->batch();
    ASSERT_TRUE(rb.ok());
    const penumbra::gpu::Batch::Range ranges[] = {{&*one}, bad};
    rb->dispatch(*k, ranges, &n, 1);
    Expected<std::vector<std::pair<std::string, double>>> rr = rb->run();
    ASSERT_FALSE(rr.ok()) << bad.offset << " " << bad.bytes;
    EXPECT_NE(rr.error().message.find("cannot bind"), std::string::npos) << rr.error().message;
  }
  Expected<penumbra::gpu::Batch> cb = c->batch();
  ASSERT_TRUE(cb.ok());
  cb->copy(*one, 0, *two, 60, 16);
  Expected<std::vector<std::pair<std::string, double>>> cr = cb->run();
  ASSERT_FALSE(cr.ok());
  EXPECT_NE(cr.error().message.find("outside its buffers"), std::string::npos)
      << cr.error().message;
}

// Without a driver (the loader finds no ICD), creating a context says so.
TEST(Gpu, NoDeviceIsAClearError) {
  // In a process of its own: the Vulkan instance is made once per process (NVIDIA's driver
  // fails after repeated instance cycles), so the driver list is read at the process's first
  // create() only.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        setenv("VK_ICD_FILENAMES", "/nonexistent/icd.json", 1);
        setenv("VK_DRIVER_FILES", "/nonexistent/icd.json", 1);
        Expected<std::shared_ptr<penumbra::gpu::Context>> c = penumbra::gpu::Context::create(true);
        if (c.ok()) std::_Exit(0);
        std::fprintf(stderr, "%s\n", c.error().message.c_str());
        std::_Exit(3);
      },
      ::testing::ExitedWithCode(3), "no Vulkan 1.1 driver found");
}

}  // namespace

namespace {

// The GPU's jump flooding finds the same seeds as the CPU's: the same distances, to sqrt's last
// bits, on a grid that is neither square nor a power of two, with walls, fog and empty space.
TEST(Gpu, JumpFloodingMatchesTheCpu) {
  std::shared_ptr<penumbra::gpu::Context> c = context();
  ASSERT_TRUE(c);
  Medium m;
  m.width = 301;
  m.height = 173;
  m.cells.assign(std::size_t(m.width) * m.height, Cell{0, 0, 0});
  m.step.assign(m.cells.size(), 0.0f);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> px(0, m.width - 1), py(0, m.height - 1);
  for (int i = 0; i < 40; ++i) m.step[std::size_t(py(rng)) * m.width + px(rng)] = kOpaque;
  for (int x = 50; x < 250; ++x) m.step[std::size_t(90) * m.width + x] = 0.3f;
  const std::vector<float> cpu = jump_flood_distance(m);
  std::vector<std::pair<std::string, double>> passes;
  Expected<std::vector<float>> gpu = flatland::gpu::jump_flood_distance(*c, m, &passes);
  ASSERT_TRUE(gpu.ok()) << gpu.error().message;
  ASSERT_EQ(gpu->size(), cpu.size());
  for (std::size_t i = 0; i < cpu.size(); ++i) {
    ASSERT_NEAR((*gpu)[i], cpu[i], 1e-6f * cpu[i]) << "cell " << i;
  }
  if (c->info().timestamp_period_ns > 0) {
    EXPECT_EQ(passes.size(), jump_flood_steps(301, 173).size() + 2);
  }
  // A grid without interacting cells: infinity everywhere, as on the CPU.
  std::fill(m.step.begin(), m.step.end(), 0.0f);
  gpu = flatland::gpu::jump_flood_distance(*c, m);
  ASSERT_TRUE(gpu.ok()) << gpu.error().message;
  for (float d : *gpu) ASSERT_TRUE(std::isinf(d));
}

}  // namespace

namespace {

// HRC's cross blur on the GPU against the CPU's: clear, foggy and opaque cells side by side, so
// every rule (opaque copied, opaque and dissimilar neighbours left out, grid edges) is used.
TEST(Gpu, CrossBlurMatchesTheCpu) {
  std::shared_ptr<penumbra::gpu::Context> c = context();
  ASSERT_TRUE(c);
  const int w = 97, h = 61;
  const std::size_t n = std::size_t(w) * h;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> tau(n), f(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const float r = u(rng);
    tau[i] = r < 0.2f ? 0.0f : r < 0.6f ? 1.0f : u(rng);
  }
  for (float& v : f) v = 10 * u(rng);
  std::vector<float> cpu(3 * n);
  hrc::cross_blur(w, h, tau.data(), w, f.data(), cpu.data());
  Expected<std::vector<float>> gpu = flatland::gpu::cross_blur(*c, w, h, tau, f);
  ASSERT_TRUE(gpu.ok()) << gpu.error().message;
  for (std::size_t i = 0; i < 3 * n; ++i) {
    ASSERT_NEAR((*gpu)[i], cpu[i], 1e-6f * cpu[i]) << "value " << i;
  }
  EXPECT_FALSE(flatland::gpu::cross_blur(*c, w, h, tau, std::vector<float>(5)).ok());
}

}  // namespace

namespace {

// A whole HRC solve on the GPU against the CPU's, on grids that are square, oblong and not powers
// of two, with walls, lights, fog and an environment, with and without the near segment and
// the blur (in the gather, or over the whole fluence), and the near fan at 0, 2 and 5 cells
// around the glowing disk's rim (the GPU's fan cells marked open rim cells at 0: 3e-2). The
// issue's bound is a relative RMSE of 1e-3.
TEST(Gpu, HrcSolveMatchesTheCpu) {
  std::shared_ptr<penumbra::gpu::Context> c = context();
  ASSERT_TRUE(c);
  struct Case {
    int w, h;
    bool near, blur;
    Storage storage = Storage::f32;
    bool blur_near = false;  // eq. 21 on the whole fluence (its own pass) instead of in the gather
    Corners corners = Corners::half;
    int near_fan = HrcOptions{}.near_fan;
    float even_weight = HrcOptions{}.even_weight;
    float fan_share = HrcOptions{}.fan_share;
  };
  for (const Case& k :
       {Case{64, 64, true, true}, Case{100, 37, true, true}, Case{45, 80, false, false},
        Case{128, 96, true, false}, Case{100, 37, true, true, Storage::f16},
        Case{96, 64, true, true, Storage::f32, true},
        Case{64, 64, true, true, Storage::f32, false, Corners::walls},
        Case{100, 37, true, true, Storage::f32, false, Corners::half, 0},
        Case{45, 80, true, true, Storage::f32, false, Corners::half, 5},
        Case{64, 64, true, true, Storage::f32, false, Corners::half, 2, 0.9f},
        Case{100, 37, true, true, Storage::f16, false, Corners::half, 2, 0.5f},
        Case{64, 64, true, true, Storage::f32, false, Corners::half, 3, 0.575f, 0.3f},
        Case{45, 80, true, true, Storage::f16, false, Corners::half, 16, 0.575f, 1.0f}}) {
    SceneDesc d;
    d.width = k.w;
    d.height = k.h;
    d.environment = {0.05f, 0.08f, 0.1f};
    d.shapes.push_back({Circle{{k.w * 0.3f, k.h * 0.5f}, 3}, Material{{6, 4, 2}, 1, {}}});
    d.shapes.push_back({Box{{k.w * 0.55f, k.h * 0.5f}, {2, k.h * 0.5f}, 15}, Material{{}, 1, {}}});
    d.shapes.push_back(
        {Circle{{k.w * 0.75f, k.h * 0.3f}, 8}, Material{{0.2f, 0.1f, 0}, 0.15f, {}}});
    const Scene s = *build_scene(d);
    const Medium m = make_medium(s);
    HrcOptions o;
    o.near_segment = k.near;
    o.cross_blur = k.blur;
    o.storage = k.storage;
    o.blur_near = k.blur_near;
    o.corners = k.corners;
    o.near_fan = k.near_fan;
    o.even_weight = k.even_weight;
    o.fan_share = k.fan_share;
    hrc::Workspace workspace;
    std::vector<float> cpu;
    std::vector<StageTime> stages;
    hrc::solve(m, s.environment, o, workspace, cpu, stages);
    RenderOptions ro;
    ro.method = Method::hrc;
    ro.hrc = o;
    std::vector<StageTime> passes;
    flatland::gpu::Solver solver(c);
    Expected<std::vector<float>> gpu = solver.render(s, plan_of(s.width, s.height, ro), passes);
    ASSERT_TRUE(gpu.ok()) << gpu.error().message;
    ASSERT_EQ(gpu->size(), cpu.size());
    double err = 0, ref = 0;
    for (std::size_t i = 0; i < cpu.size(); ++i) {
      err += double((*gpu)[i] - cpu[i]) * ((*gpu)[i] - cpu[i]);
      ref += double(cpu[i]) * cpu[i];
    }
    const double rel = std::sqrt(err / ref);
    EXPECT_LT(rel, 1e-3) << k.w << "x" << k.h << " near fan " << k.near_fan << " fan share "
                         << k.fan_share;
    std::printf("%dx%d: relative RMSE GPU against CPU %.2e\n", k.w, k.h, rel);
  }
}

}  // namespace

namespace {

// render() with --device gpu runs HRC on the GPU and agrees with the CPU; what the GPU does not
// run yet is refused with a message; auto falls back to the CPU where there is no hardware GPU.
TEST(Gpu, RenderOnTheGpuDevice) {
  SceneDesc d;
  d.width = 80;
  d.height = 60;
  d.environment = {0.02f, 0.02f, 0.03f};
  d.shapes.push_back({Circle{{20, 30}, 4}, Material{{5, 4, 3}, 1, {}}});
  d.shapes.push_back({Box{{45, 30}, {3, 30}, 0}, Material{{}, 1, {0.5f, 0.5f, 0.5f}}});
  const Scene s = *build_scene(d);
  RenderOptions o;
  o.method = Method::hrc;
  Expected<RenderResult> cpu = render(s, o);
  ASSERT_TRUE(cpu.ok()) << cpu.error().message;
  EXPECT_EQ(cpu->device, "cpu");
  for (Device dev : {Device::gpu, Device::auto_}) {
    o.device = dev;
    Renderer renderer;  // twice: the second render reuses the context
    for (int i = 0; i < 2; ++i) {
      Expected<RenderResult> r = renderer.render(s, o);
      ASSERT_TRUE(r.ok()) << r.error().message;
      if (dev == Device::gpu) {
        EXPECT_NE(r->device, "cpu");
        EXPECT_TRUE(std::any_of(r->stages.begin(), r->stages.end(),
                                [](const StageTime& st) { return st.name == "gpu merge down R"; }));
      }
      double err = 0, ref = 0;
      for (std::size_t k = 0; k < 3 * s.cells(); ++k) {
        const double a = r->fluence.data()[k], b = cpu->fluence.data()[k];
        err += (a - b) * (a - b);
        ref += b * b;
      }
      EXPECT_LT(std::sqrt(err / ref), 1e-3) << to_string(dev);
    }
  }
  o.device = Device::gpu;
  o.method = Method::pt;  // the path tracer is not on the GPU: refused, not run on the CPU
  Expected<RenderResult> r = render(s, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("path tracer runs on the CPU only"), std::string::npos)
      << r.error().message;
  o.device = Device::auto_;
  o.pt.spp = 1;
  Expected<RenderResult> pt = render(s, o);
  ASSERT_TRUE(pt.ok()) << pt.error().message;
  EXPECT_EQ(pt->device, "cpu");
  o.device = Device::auto_;  // not ported: the CPU does it
  o.method = Method::rc;
  o.rc.fix = MergeFix::none;
  o.rc.extend = true;
  Expected<RenderResult> fallback = render(s, o);
  ASSERT_TRUE(fallback.ok()) << fallback.error().message;
  EXPECT_EQ(fallback->device, "cpu");
  o.device = Device::gpu;
  o.rc.fix = MergeFix::none;
  o.rc.extend = true;
  r = render(s, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("extension runs on the CPU only"), std::string::npos)
      << r.error().message;
}

std::vector<float> pixels(const ImageRgb& f) {
  return std::vector<float>(f.data(), f.data() + f.size());
}

// A scene with walls, lights, fog, a thin wall and an environment.
Scene mixed_scene(int w, int h) {
  SceneDesc d;
  d.width = w;
  d.height = h;
  d.environment = {0.05f, 0.08f, 0.1f};
  d.shapes.push_back({Circle{{w * 0.3f, h * 0.5f}, 3}, Material{{6, 4, 2}, 1, {}}});
  d.shapes.push_back(
      {Box{{w * 0.55f, h * 0.5f}, {1, h * 0.35f}, 15}, Material{{}, 1, {0.7f, 0.7f, 0.7f}}});
  d.shapes.push_back(
      {Circle{{w * 0.75f, h * 0.3f}, 8}, Material{{0.2f, 0.1f, 0}, 0.15f, {0.5f, 0.5f, 0.5f}}});
  return *build_scene(d);
}

// Radiance cascades on the GPU against the CPU: every merge mode, both branching factors, a
// probe spacing of 2, pre-averaging, the plain DDA, more bounces, on grids that are square,
// oblong and not powers of two. The issue's bound is a relative RMSE of 1e-3; measured: 1e-7.
TEST(Gpu, RcMatchesTheCpu) {
  struct Case {
    const char* name;
    int w, h;
    RenderOptions o;
  };
  std::vector<Case> cases;
  auto add = [&](const char* name, int w, int h, auto edit) {
    RenderOptions o;
    o.method = Method::rc;
    edit(o);
    cases.push_back({name, w, h, o});
  };
  add("bilinear", 96, 96, [](RenderOptions&) {});
  add("none", 100, 37, [](RenderOptions& o) { o.rc.fix = MergeFix::none; });
  add("nearest", 45, 80, [](RenderOptions& o) { o.rc.fix = MergeFix::nearest; });
  add("branching 2", 64, 64, [](RenderOptions& o) { o.rc.branching = 2, o.rc.interval = 4; });
  add("spacing 2, 8 directions", 70, 50,
      [](RenderOptions& o) { o.rc.probe_spacing = 2, o.rc.directions = 8; });
  add("preaverage", 64, 48, [](RenderOptions& o) { o.rc.preaverage = true; });
  add("plain DDA", 64, 64, [](RenderOptions& o) { o.distance_field = false, o.blocks = false; });
  add("3 bounces", 64, 64, [](RenderOptions& o) { o.bounces = 3; });
  add("one row", 40, 1, [](RenderOptions&) {});
  for (const Case& c : cases) {
    const Scene s = mixed_scene(c.w, c.h);
    const RenderResult cpu = penumbra::testing::render_valid(s, c.o);
    RenderOptions g = c.o;
    g.device = Device::gpu;
    const RenderResult gpu = penumbra::testing::render_valid(s, g);
    EXPECT_NE(gpu.device, "cpu");
    ASSERT_EQ(gpu.fluence.size(), cpu.fluence.size()) << c.name;
    const double rel = relative_rmse(gpu.fluence, cpu.fluence);
    EXPECT_LT(rel, 1e-3) << c.name;
    std::printf("%-24s %dx%d: relative RMSE GPU against CPU %.2e\n", c.name, c.w, c.h, rel);
    EXPECT_EQ(gpu.intervals, cpu.intervals) << c.name;
  }
}

// The scene stays on the GPU: a second render of the same scene uploads nothing and rebuilds
// neither the medium nor the distance field; an edit uploads only the rows it touched. Each
// result equals a fresh renderer's, bit for bit.
TEST(Gpu, SceneStaysOnTheGpuBetweenRenders) {
  for (Method method : {Method::rc, Method::hrc}) {
    const int w = 72, h = 56;
    Scene s = mixed_scene(w, h);
    RenderOptions o;
    o.method = method;
    o.device = Device::gpu;
    Renderer kept;
    auto fresh = [&](const Scene& scene) { return penumbra::testing::render_valid(scene, o); };
    auto has = [](const RenderResult& r, const std::string& name) {
      return std::any_of(r.stages.begin(), r.stages.end(),
                         [&](const StageTime& st) { return st.name == name; });
    };
    Expected<RenderResult> first = kept.render(s, o);
    ASSERT_TRUE(first.ok()) << first.error().message;
    const std::uint64_t scene_bytes = std::uint64_t(w) * h * 7 * sizeof(float);
    EXPECT_GE(first->uploaded_bytes, scene_bytes);
    EXPECT_TRUE(has(*first, "gpu medium"));
    EXPECT_GT(first->gpu_memory_bytes, scene_bytes);

    Expected<RenderResult> again = kept.render(s, o);
    ASSERT_TRUE(again.ok()) << again.error().message;
    EXPECT_EQ(again->uploaded_bytes, 0u);
    EXPECT_FALSE(has(*again, "gpu medium"));
    EXPECT_FALSE(has(*again, "gpu distance field"));
    EXPECT_EQ(pixels(again->fluence), pixels(first->fluence));

    // A light painted into rows 20..22: three rows go up, and the picture is a fresh render's.
    for (int y = 20; y <= 22; ++y)
      for (int x = 10; x <= 12; ++x) {
        const std::size_t i = s.index(x, y);
        s.opacity[i] = 1;
        s.emission[3 * i] = s.emission[3 * i + 1] = s.emission[3 * i + 2] = 3;
      }
    Expected<RenderResult> edited = kept.render(s, o);
    ASSERT_TRUE(edited.ok()) << edited.error().message;
    EXPECT_EQ(edited->uploaded_bytes, 3 * std::uint64_t(w) * 7 * sizeof(float));
    EXPECT_TRUE(has(*edited, "gpu medium"));
    EXPECT_EQ(pixels(edited->fluence), pixels(fresh(s).fluence)) << to_string(method);
    EXPECT_NE(pixels(edited->fluence), pixels(first->fluence));

    // New emission alone (a light's colour): the medium stays, one row goes up.
    s.emission[3 * s.index(11, 21)] = 5;
    Expected<RenderResult> recoloured = kept.render(s, o);
    ASSERT_TRUE(recoloured.ok()) << recoloured.error().message;
    EXPECT_EQ(recoloured->uploaded_bytes, std::uint64_t(w) * 7 * sizeof(float));
    EXPECT_FALSE(has(*recoloured, "gpu medium"));
    EXPECT_EQ(pixels(recoloured->fluence), pixels(fresh(s).fluence)) << to_string(method);

    // Another grid size: everything goes up again.
    const Scene other = mixed_scene(40, 30);
    Expected<RenderResult> resized = kept.render(other, o);
    ASSERT_TRUE(resized.ok()) << resized.error().message;
    EXPECT_GE(resized->uploaded_bytes, std::uint64_t(40) * 30 * 7 * sizeof(float));
    EXPECT_EQ(pixels(resized->fluence), pixels(fresh(other).fluence));
  }
}

// What the solver allocates on the device is what it estimated, to the byte, across methods,
// storage, the blur, bounces and the distance field; buffers of options no longer used are
// freed.
TEST(Gpu, DeviceMemoryIsWhatTheEstimateSays) {
  std::shared_ptr<penumbra::gpu::Context> c = context();
  ASSERT_TRUE(c);
  flatland::gpu::Solver solver(c);
  const Scene s = mixed_scene(96, 80);
  struct Case {
    const char* name;
    RenderOptions o;
  };
  std::vector<Case> cases;
  auto add = [&](const char* name, auto edit) {
    RenderOptions o;
    o.device = Device::gpu;
    edit(o);
    cases.push_back({name, o});
  };
  add("rc", [](RenderOptions& o) { o.method = Method::rc; });
  add("rc 2 bounces, 16 directions",
      [](RenderOptions& o) { o.method = Method::rc, o.bounces = 2, o.rc.directions = 16; });
  add("hrc", [](RenderOptions& o) { o.method = Method::hrc; });
  add("hrc f16", [](RenderOptions& o) { o.method = Method::hrc, o.hrc.storage = Storage::f16; });
  add("hrc, no blur", [](RenderOptions& o) { o.method = Method::hrc, o.hrc.cross_blur = false; });
  add("rc, plain DDA", [](RenderOptions& o) { o.method = Method::rc, o.distance_field = false; });
  for (const Case& k : cases) {
    const Plan plan = plan_of(s.width, s.height, k.o);
    std::vector<StageTime> stages;
    Expected<std::vector<float>> f = solver.render(s, plan, stages);
    ASSERT_TRUE(f.ok()) << k.name << ": " << f.error().message;
    const std::uint64_t estimate = flatland::gpu::Solver::device_bytes(plan);
    const std::uint64_t held = solver.allocated_bytes();
    EXPECT_EQ(held, estimate) << k.name;
  }
}

// A cascade larger than one binding is merged a slab of directions at a time, and cascade 0 is
// summed into the fluence a slab at a time: with the binding limited to two directions of
// cascade 0, the result is the one-binding result (merges to the bit, the fluence's sums in
// another order).
TEST(Gpu, LargeCascadesAreMergedInSlabs) {
  std::shared_ptr<penumbra::gpu::Context> c = context();
  ASSERT_TRUE(c);
  struct Case {
    int w, h, directions, branching;
    std::uint64_t alignment;  // 256: slabs start inside an aligned block (33x7: 3696 B a direction)
  };
  for (const Case& k : {Case{64, 48, 8, 4, 0}, Case{33, 7, 4, 4, 256}, Case{33, 7, 4, 2, 256}})
    for (MergeFix fix : {MergeFix::bilinear, MergeFix::none, MergeFix::nearest}) {
      const Scene s = mixed_scene(k.w, k.h);
      RenderOptions o;
      o.method = Method::rc;
      o.device = Device::gpu;
      o.rc.fix = fix;
      o.rc.directions = k.directions;
      o.rc.branching = k.branching;
      const Plan plan = plan_of(s.width, s.height, o);
      const std::uint64_t direction = std::uint64_t(k.w) * k.h * 16;  // of cascade 0
      const std::uint64_t align = std::max<std::uint64_t>(k.alignment, c->info().offset_alignment);
      flatland::gpu::Solver whole(c), slabs(c);
      slabs.limit_binding(2 * direction + align, k.alignment);  // two directions of cascade 0
      std::vector<StageTime> stages;
      Expected<std::vector<float>> a = whole.render(s, plan, stages);
      Expected<std::vector<float>> b = slabs.render(s, plan, stages);
      ASSERT_TRUE(a.ok()) << a.error().message;
      ASSERT_TRUE(b.ok()) << b.error().message;
      double err = 0, ref = 0;
      for (std::size_t i = 0; i < a->size(); ++i) {
        err += double((*a)[i] - (*b)[i]) * ((*a)[i] - (*b)[i]);
        ref += double((*a)[i]) * (*a)[i];
      }
      EXPECT_LT(std::sqrt(err / ref), 1e-6) << k.w << "x" << k.h << " " << to_string(fix);
      EXPECT_NE(*a, *b) << "the slabs were not used";  // the fluence's sums differ in order
      slabs.limit_binding(direction / 2);              // not even one direction: refused, not wrong
      Expected<std::vector<float>> none = slabs.render(s, plan, stages);
      ASSERT_FALSE(none.ok());
      EXPECT_NE(none.error().message.find("one binding"), std::string::npos)
          << none.error().message;
    }
}

// A render that fails part way through recording (here a cascade direction larger than the
// binding the test allows, after the scene's upload was recorded) leaves nothing stale: the
// next render of an edited scene on the same solver equals a fresh solver's.
TEST(Gpu, FailedRenderLeavesNoStaleState) {
  std::shared_ptr<penumbra::gpu::Context> c = context();
  ASSERT_TRUE(c);
  Scene s = mixed_scene(64, 48);
  RenderOptions o;
  o.method = Method::rc;
  o.device = Device::gpu;
  const Plan plan = plan_of(s.width, s.height, o);
  flatland::gpu::Solver kept(c);
  std::vector<StageTime> stages;
  ASSERT_TRUE(kept.render(s, plan, stages).ok());
  s.opacity[s.index(30, 20)] = 1;  // an edit: its row is recorded for upload, then the render fails
  kept.limit_binding(1024);
  ASSERT_FALSE(kept.render(s, plan, stages).ok());
  kept.limit_binding(0);
  Expected<std::vector<float>> after = kept.render(s, plan, stages);
  ASSERT_TRUE(after.ok()) << after.error().message;
  flatland::gpu::Solver fresh(c);
  Expected<std::vector<float>> expected = fresh.render(s, plan, stages);
  ASSERT_TRUE(expected.ok()) << expected.error().message;
  EXPECT_EQ(*after, *expected);
  EXPECT_GE(kept.uploaded_bytes(), std::uint64_t(64) * 48 * 7 * sizeof(float));
}

// A render larger than the device's memory is refused before anything is allocated, with the
// need and the device named.
TEST(Gpu, RefusesWorkLargerThanTheDevice) {
  penumbra::gpu::DeviceInfo small;
  small.name = "a small GPU";
  small.device_local_bytes = std::uint64_t(64) << 20;
  RenderOptions o;
  o.method = Method::rc;
  o.device = Device::gpu;
  Status st = flatland::gpu::Solver::check_memory(small, plan_of(4096, 4096, o, false));
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("4096x4096 grid needs"), std::string::npos)
      << st.error().message;
  EXPECT_NE(st.error().message.find("a small GPU"), std::string::npos);
  EXPECT_TRUE(flatland::gpu::Solver::check_memory(small, plan_of(256, 256, o, false)).ok());
  o.method = Method::hrc;
  EXPECT_FALSE(flatland::gpu::Solver::check_memory(small, plan_of(4096, 4096, o, false)).ok());
}

}  // namespace

namespace {

// 1-D work is folded so that x stays within the device's limit, and the folded kernel still
// covers every element exactly once (a limit of 3 groups in x forces 5 rows of groups).
TEST(Gpu, OneDimensionalWorkFoldsIntoTwo) {
  penumbra::gpu::DeviceInfo info;
  info.max_workgroups_x = 3;
  penumbra::gpu::Groups g = penumbra::gpu::groups_1d(256 * 13 + 1, 256, info);
  EXPECT_EQ(g.x, 3u);
  EXPECT_EQ(g.y, 5u);
  info.max_workgroups_x = 65535;
  g = penumbra::gpu::groups_1d(std::size_t(16384) * 16384, 256, info);
  EXPECT_LE(g.x, 65535u);
  EXPECT_GE(std::uint64_t(g.x) * g.y * 256, std::uint64_t(16384) * 16384);
  std::shared_ptr<penumbra::gpu::Context> c = context();
  ASSERT_TRUE(c);
  const std::uint32_t n = 256 * 13 + 1;
  Expected<penumbra::gpu::Buffer> in = c->buffer(n * sizeof(float)),
                                  out = c->buffer(n * sizeof(float));
  ASSERT_TRUE(in.ok() && out.ok());
  for (std::uint32_t i = 0; i < n; ++i) in->as<float>()[i] = 1.0f - 1.0f / float(i + 2);
  std::fill(out->as<float>(), out->as<float>() + n, -1.0f);
  Expected<penumbra::gpu::Kernel> k =
      c->kernel("medium", flatland::gpu::shaders::medium(), 2, sizeof(std::uint32_t));
  ASSERT_TRUE(k.ok());
  Expected<penumbra::gpu::Batch> b = c->batch();
  ASSERT_TRUE(b.ok());
  penumbra::gpu::Buffer* buffers[] = {&*in, &*out};
  b->dispatch(*k, buffers, &n, 3, 5);  // folded as groups_1d does with a limit of 3
  ASSERT_TRUE(b->run().ok());
  for (std::uint32_t i = 0; i < n; ++i)
    ASSERT_NEAR(out->as<float>()[i], extinction(in->as<float>()[i]), 1e-5f * 10) << i;
}

}  // namespace
