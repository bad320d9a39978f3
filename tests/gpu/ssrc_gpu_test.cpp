// The screen-space cascades on the GPU (Mesa's lavapipe in CI) against the CPU path: the same
// image up to float rounding on a sky over a plane, a closed box lit from its ceiling and a
// sphere light over a floor, in every merge and gather, at 8, 16 and 32 sectors, over two
// bounces; the uniform sky's closed form; a store held in slabs gives the same bits; --device gpu
// is refused for the other 3D methods.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "gpu/vulkan.hpp"
#include "image_metrics.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/embree/ray_scene.hpp"
#include "spaceland/gbuffer.hpp"
#include "spaceland/scene_builders.hpp"
#include "spaceland/ssrc/gpu.hpp"
#include "spaceland/ssrc/ssrc.hpp"

namespace penumbra::spaceland {
namespace {

using namespace penumbra::spaceland::testing;
using penumbra::testing::relative_rmse;

RenderOptions ssrc(Device device, SpwiMerge merge, SpwiGather gather, int sectors, int bounces) {
  RenderOptions o;
  o.method = Method::ssrc;
  o.device = device;
  o.ssrc.merge = merge;
  o.ssrc.gather = gather;
  o.ssrc.sectors = sectors;
  o.bounces = bounces;
  return o;
}

// A closed box 2 wide (walls 0.7, a red and a green side wall), a square light in its ceiling and
// a block on its floor, seen from inside near the front wall: 80 x 60 unless told.
Scene lit_box(int w = 80, int h = 60) {
  Scene s;
  s.camera = camera({0, 0, 0.9f}, {0, 0.2f, -1}, w, h, 80);
  const std::uint32_t white = add_material(s, {0.7f, 0.7f, 0.7f});
  const std::uint32_t red = add_material(s, {0.7f, 0.1f, 0.1f});
  const std::uint32_t green = add_material(s, {0.1f, 0.7f, 0.1f});
  add_quad(s, {-1, -1, -1}, {2, 0, 0}, {0, 0, 2}, white);  // floor
  add_quad(s, {-1, 1, -1}, {0, 0, 2}, {2, 0, 0}, white);   // ceiling
  add_quad(s, {-1, -1, -1}, {0, 2, 0}, {2, 0, 0}, white);  // back
  add_quad(s, {-1, -1, 1}, {2, 0, 0}, {0, 2, 0}, white);   // front, behind the camera
  add_quad(s, {-1, -1, -1}, {0, 0, 2}, {0, 2, 0}, red);    // left
  add_quad(s, {1, -1, -1}, {0, 2, 0}, {0, 0, 2}, green);   // right
  add_quad(s, {-0.3f, 0.99f, -0.5f}, {0.6f, 0, 0}, {0, 0, 0.6f},
           add_material(s, {0, 0, 0}, {8, 8, 8}));
  add_box(s, {-0.5f, -1, -0.6f}, {0.1f, -0.2f, 0.0f}, white);
  return s;
}

// A sphere light (radius 0.3, Le 30) over a wide floor, 96 x 72.
Scene sphere_over_floor() {
  Scene s = wide_floor();
  s.camera = camera({0, 2, 4}, {0, 0, 0}, 96, 72, 60);
  add_sphere(s, {0.3f, 1, -0.5f}, 0.3f, add_material(s, {0, 0, 0}, {30, 30, 30}));
  return s;
}

struct Case {
  const char* name;
  Scene scene;
};

// The up-front memory check counts the port's buffers (gpu_bytes): what a render on the GPU
// reports it used stays within the CPU's estimate plus the port's, in either gather, and a
// limit between the CPU's need and the GPU's refuses the GPU's render before it starts.
TEST(SsrcGpu, TheMemoryCheckCountsThePortsBuffers) {
  const Scene s = lit_box();
  for (SpwiGather gather : {SpwiGather::probe, SpwiGather::pixel}) {
    RenderOptions o = ssrc(Device::gpu, SpwiMerge::bilateral, gather, 32, 1);
    const ssrc::Layout l = ssrc::make_layout(s.camera.width, s.camera.height, o.ssrc);
    const RenderResult gpu = render_ok(s, o);
    EXPECT_GT(gpu.memory_bytes, l.bytes());
    EXPECT_LE(gpu.memory_bytes, l.bytes() + ssrc::gpu_bytes(l, o.ssrc) + (64u << 20))
        << "gather " << to_string(gather);  // 64 MiB: the BVH, the G-buffer and the image
    o.max_memory = l.bytes() + ssrc::gpu_bytes(l, o.ssrc) / 2;
    const Expected<RenderResult> refused = render(s, o);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("max_memory"), std::string::npos)
        << refused.error().message;
  }
}

// The kernels shade Lambertian pixels only: a glossy material is refused by name, with the CPU
// named as the way on; the CPU renders it.
TEST(SsrcGpu, GlossyMaterialsAreRefusedForTheCpu) {
  Scene s = lit_box(32, 24);
  s.materials[0].metallic = 1;
  s.materials[0].roughness = 0.4f;
  RenderOptions o = ssrc(Device::gpu, SpwiMerge::bilateral, SpwiGather::probe, 32, 1);
  const Expected<RenderResult> refused = render(s, o);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("ssrc's glossy materials (their specular lobe) are on "
                                         "the CPU only; use `device` cpu"),
            std::string::npos)
      << refused.error().message;
  o.device = Device::cpu;
  EXPECT_TRUE(render(s, o).ok());
}

// Every merge and gather at 8, 16 and 32 sectors over two bounces, each scene. The kernels do
// the CPU's float operations in its order, with no multiply-add fused (`precise`): on lavapipe
// (LLVM, IEEE division and sqrt) the images are the same bits (measured: relative RMSE 0 in all
// 54 cases), held to 1e-6. A hardware GPU's division and sqrt may round differently (2.5 ulp
// in Vulkan) and move a sample on a sector's edge: there the bound is 1e-3.
TEST(SsrcGpu, MatchesTheCpuInEveryMergeGatherAndSectorCount) {
  Expected<std::shared_ptr<penumbra::gpu::Context>> c = penumbra::gpu::Context::create(true);
  ASSERT_TRUE(c.ok()) << c.error().message;
  const double bound = (*c)->info().cpu ? 1e-6 : 1e-3;
  const Case cases[] = {{"sky over a plane", sky_plane()},
                        {"lit box", lit_box()},
                        {"sphere light over a floor", sphere_over_floor()}};
  double worst = 0;
  for (const Case& k : cases)
    for (SpwiMerge m : {SpwiMerge::bilinear, SpwiMerge::bilateral, SpwiMerge::bilinear3d})
      for (SpwiGather gather : {SpwiGather::probe, SpwiGather::pixel})
        for (int sectors : {8, 16, 32}) {
          const RenderResult cpu = render_ok(k.scene, ssrc(Device::cpu, m, gather, sectors, 2));
          const RenderResult gpu = render_ok(k.scene, ssrc(Device::gpu, m, gather, sectors, 2));
          EXPECT_EQ(gpu.device, "gpu");
          const double e = relative_rmse(gpu.radiance, cpu.radiance);
          worst = std::max(worst, e);
          EXPECT_LT(e, bound) << k.name << ", merge " << to_string(m) << ", gather "
                              << to_string(gather) << ", " << sectors << " sectors";
        }
  std::printf("%s: worst relative RMSE, GPU against CPU: %.3g\n", (*c)->info().name.c_str(), worst);
}

// The other options: the back faces' solids and an infinite thickness, fewer steps and
// directions, a wider probe spacing and a longer interval, fixed cascades, three bounces, on an
// image whose sides are odd (the pyramid's odd edges, probes clamped to the last pixel). The
// same bound as above (measured: 0 on lavapipe).
TEST(SsrcGpu, MatchesTheCpuWithTheOtherOptions) {
  Expected<std::shared_ptr<penumbra::gpu::Context>> c = penumbra::gpu::Context::create(true);
  ASSERT_TRUE(c.ok()) << c.error().message;
  const double bound = (*c)->info().cpu ? 1e-6 : 1e-3;
  const Scene scenes[] = {lit_box(67, 45), sphere_over_floor()};
  for (const Scene& scene : scenes)
    for (int variant = 0; variant < 3; ++variant) {
      RenderOptions o = ssrc(Device::cpu, SpwiMerge::bilateral,
                             variant == 1 ? SpwiGather::pixel : SpwiGather::probe, 16, 3);
      o.ssrc.backfaces = variant == 0;
      o.ssrc.thickness = variant == 1 ? 1e30f : 0.05f;
      o.ssrc.steps = variant == 2 ? 4 : 16;
      o.ssrc.directions = variant == 2 ? 8 : 16;
      o.ssrc.probe_spacing = variant == 2 ? 3 : 0;
      o.ssrc.interval = variant == 2 ? 10 : 0;
      o.ssrc.cascades = variant == 2 ? 3 : 0;
      const RenderResult cpu = render_ok(scene, o);
      o.device = Device::gpu;
      const RenderResult gpu = render_ok(scene, o);
      EXPECT_LT(relative_rmse(gpu.radiance, cpu.radiance), bound)
          << scene.camera.width << " x " << scene.camera.height << ", variant " << variant;
    }
}

// The closed form holds on the GPU too: a uniform sky over an open plane gives a L.
TEST(SsrcGpu, UniformSkyOverAnOpenPlaneIsAL) {
  for (int bounces : {1, 2}) {
    const RenderResult r = render_ok(
        sky_plane(), ssrc(Device::gpu, SpwiMerge::bilateral, SpwiGather::probe, 32, bounces));
    EXPECT_LT(sky_plane_error(r.radiance), 0.015) << bounces << " bounces";
  }
}

// The report names the device and times the GPU's stages.
TEST(SsrcGpu, ReportsTheDeviceAndEachStage) {
  const RenderResult r =
      render_ok(sky_plane(), ssrc(Device::gpu, SpwiMerge::bilateral, SpwiGather::probe, 32, 2));
  EXPECT_EQ(r.device, "gpu");
  auto has = [&](const std::string& name) {
    for (const StageTime& s : r.stages)
      if (s.name == name) return true;
    return false;
  };
  for (const char* name :
       {"GPU device", "upload", "cascade 0 (bounce 1)", "gather (bounce 2)", "readback"})
    EXPECT_TRUE(has(name)) << name;
}

// The CPU's preparation with the GPU's cascades, every binding held to `Limit` bytes.
template <std::uint64_t Limit>
Expected<ImageRgb> held_port(const SolveContext& ctx, const SsrcOptions& o, const ssrc::Prepared& p,
                             SolveReport& report) {
  return ssrc::render_gpu(ctx, o, p, report, Limit);
}

Expected<ImageRgb> render_with(const Scene& s, const RenderOptions& o, ssrc::Port port) {
  Expected<RayScene> rays = RayScene::build(s);
  if (!rays) return rays.error();
  const GBuffer g = make_gbuffer(s, *rays);
  SolveContext ctx{s, *rays, g, o.bounces, std::uint64_t(1) << 32, o.sun_rays};
  const ssrc::Layout layout = ssrc::make_layout(g.width, g.height, o.ssrc);
  SolveReport report;
  return ssrc::render(ctx, o.ssrc, layout, report, port);
}

// A store larger than one binding is marched and gathered a slab of probes or pixels at a time,
// with the same bits as in one piece; a binding too small for the image's other buffers is
// refused, naming the port.
TEST(SsrcGpu, SlabsOfTheStoreGiveTheSameBits) {
  const Scene s = lit_box();
  for (SpwiGather gather : {SpwiGather::probe, SpwiGather::pixel}) {
    const RenderOptions o = ssrc(Device::gpu, SpwiMerge::bilinear3d, gather, 32, 2);
    Expected<ImageRgb> whole = render_with(s, o, ssrc::render_gpu);
    ASSERT_TRUE(whole.ok()) << whole.error().message;
    // Cascade 0's store is 40 x 30 probes of 16 directions of 8 bins: 1.8 MiB, here in slabs.
    Expected<ImageRgb> slabs = render_with(s, o, held_port<256 * 1024>);
    ASSERT_TRUE(slabs.ok()) << slabs.error().message;
    ASSERT_EQ(whole->size(), slabs->size());
    for (std::size_t i = 0; i < whole->size(); ++i)
      ASSERT_EQ(whole->data()[i], slabs->data()[i]) << "float " << i;
  }
  const RenderOptions o = ssrc(Device::gpu, SpwiMerge::bilateral, SpwiGather::probe, 32, 1);
  Expected<ImageRgb> refused = render_with(s, o, held_port<1024>);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("ssrc on the GPU"), std::string::npos)
      << refused.error().message;
}

// Only ssrc has a 3D GPU port, for every option but --offscreen world.
TEST(SsrcGpu, TheOtherThreeDMethodsStillRefuseTheGpu) {
  for (Method m : {Method::pt, Method::spwi, Method::grid}) {
    RenderOptions o;
    o.method = m;
    o.device = Device::gpu;
    const Status st = check_options(o);
    ASSERT_FALSE(st.ok()) << to_string(m);
    EXPECT_NE(st.error().message.find("runs on the CPU only"), std::string::npos)
        << st.error().message;
  }
  RenderOptions o;
  o.method = Method::ssrc;
  o.device = Device::gpu;
  EXPECT_TRUE(check_options(o).ok());
  // --offscreen world's exact rays are Embree's, on the CPU.
  o.ssrc.offscreen = SsrcOffscreen::world;
  const Status st = check_options(o);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("`ssrc.offscreen` world traces rays through the scene"),
            std::string::npos)
      << st.error().message;
  o.device = Device::cpu;
  EXPECT_TRUE(check_options(o).ok());
  // So is --merge fix, which marches on the CPU only.
  o = RenderOptions{};
  o.method = Method::ssrc;
  o.device = Device::gpu;
  o.ssrc.merge = SpwiMerge::fix;
  const Status fix = check_options(o);
  ASSERT_FALSE(fix.ok());
  EXPECT_NE(fix.error().message.find("`ssrc.merge` fix is on the CPU only"), std::string::npos)
      << fix.error().message;
  o.device = Device::cpu;
  EXPECT_TRUE(check_options(o).ok());
}

}  // namespace
}  // namespace penumbra::spaceland
