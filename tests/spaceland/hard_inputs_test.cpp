// Hard inputs to the 3D world (issue 37): values the format accepts render or are refused with a
// message, never a crash (Embree asserts on rays past 1.8e18), never a wrong picture with success.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "scene_builders.hpp"
#include "spaceland/camera.hpp"
#include "spaceland/grid/grid.hpp"

namespace penumbra::spaceland {
namespace {

using testing::add_floor;
using testing::add_material;
using testing::add_sphere;
using testing::camera;

bool all_finite(const ImageRgb& img) {
  for (std::size_t i = 0; i < img.size(); ++i)
    if (!std::isfinite(img.data()[i])) return false;
  return true;
}

void expect_error(const Status& s, const std::string& start, const std::string& words) {
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().message.rfind(start, 0), 0u) << s.error().message;
  EXPECT_NE(s.error().message.find(words), std::string::npos) << s.error().message;
}

// A view direction or an `up` of length 1e-30 squared to 0 in float: NaN rays, then Embree's
// assertion. The basis is found in double, so they are the unit vectors' rays.
TEST(HardInputs, TinyViewDirectionAndUpGiveTheUnitVectorsRays) {
  const Camera unit = camera({0, 0, 0}, {1, 0, 0}, 7, 5, 50, {0, 1, 0});
  const Camera tiny = camera({0, 0, 0}, {1e-30f, 0, 0}, 7, 5, 50, {0, 1e-30f, 0});
  const CameraRays a(unit), b(tiny);
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 7; ++i)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(a.direction(i, j)[k], b.direction(i, j)[k]);
  Scene s;
  s.camera = tiny;
  add_floor(s, 5, {0.5f, 0.5f, 0.5f});
  s.camera.position = {0, 1, 0};
  s.camera.look_at = {1e-30f, 1, 0};
  EXPECT_TRUE(check_scene(s).ok());
}

// What lies past the world's bound (1e15) is refused in a scene built in code too, by object.
TEST(HardInputs, ShapesPastTheWorldAreRefusedNamingTheObject) {
  Scene s;
  s.camera = camera({0, 1, 4}, {0, 0, 0}, 8, 6);
  add_floor(s, 5, {0.5f, 0.5f, 0.5f});
  add_sphere(s, {0, 0, 2e15f}, 1, add_material(s, {0.5f, 0.5f, 0.5f}));
  expect_error(check_scene(s), "<code>: objects[1]: ", "the shape reaches z = 2e+15");
  s.spheres.clear();
  testing::add_box(s, {0, 0, 0}, {1, 1, 1e20f}, 0);
  expect_error(check_scene(s),
               "<code>: objects[2]: ", "vertex 4 (in world space) reaches z = 1e+20");
  s.meshes.clear();
  s.disks[0].radius = 1e30f;
  expect_error(check_scene(s), "<code>: objects[0]: ", "the shape reaches x = -1e+30");
  s.disks[0].radius = 5;
  s.camera.position = {0, 1.9e18f, 0};
  expect_error(check_scene(s), "<code>: camera.position: ", "past the largest world coordinate");
}

// A mesh's values that are not finite (a transform's doing) are named by the document's object and
// the vertex, not by the scene's internal arrays ("meshes[3].normals[0][1]").
TEST(HardInputs, MeshValuesAreNamedByTheirObject) {
  Scene s;
  s.camera = camera({0, 1, 4}, {0, 0, 0}, 8, 6);
  add_floor(s, 5, {0.5f, 0.5f, 0.5f});
  testing::add_quad(s, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0);
  s.objects.back() = "objects[1] (mesh)";
  TriangleMesh& m = s.meshes.back();
  m.normals.assign(m.positions.size(), {0, 0, 1});
  m.normals[2] = {0, NAN, 1};
  expect_error(check_scene(s),
               "<code>: objects[1].file: ", "the normal of vertex 2 is not finite: [0, nan, 1]");
  m.normals[2] = {0, 0, 1};
  m.uvs.assign(m.positions.size(), {0, 0});
  m.uvs[1] = {INFINITY, 0};
  expect_error(check_scene(s), "<code>: objects[1].file: ",
               "the texture coordinates of vertex 1 are not finite: [inf, 0]");
}

// At the bound every method renders: a small lit scene 9e14 from the origin, seen from there, and
// one at the origin with a far sphere (the probe grid's bounds then span the world).
TEST(HardInputs, ScenesAtTheWorldsEdgeRenderInEveryMethod) {
  for (float at : {9e14f, 0.0f}) {
    Scene s;
    const Vec3 o{at, 0, 0};
    s.camera = camera(o + Vec3{0, 1, 4}, o, 8, 6);
    Disk floor;
    floor.center = o;
    floor.radius = 5;
    floor.material = add_material(s, {0.5f, 0.5f, 0.5f});
    floor.object = testing::add_object(s, "disk");
    s.disks.push_back(floor);
    add_sphere(s, o + Vec3{0, 1, 0}, 0.3f, add_material(s, {}, {5, 5, 5}));
    if (at == 0) add_sphere(s, {-9e14f, 0, 0}, 1e10f, 0);
    for (Method m : {Method::pt, Method::spwi, Method::grid}) {
      RenderOptions opt = testing::pt(1, 2);
      opt.method = m;
      const Expected<RenderResult> r = render(s, opt);
      ASSERT_TRUE(r.ok()) << to_string(m) << " at " << at << ": " << r.error().message;
      EXPECT_TRUE(all_finite(r->radiance)) << to_string(m) << " at " << at;
      // The far sphere makes the grid's voxels useless near the camera: said, not silent.
      const bool coarse = m == Method::grid && at == 0;
      ASSERT_EQ(r->warnings.size(), coarse ? 1u : 0u) << to_string(m) << " at " << at;
      if (coarse) {
        EXPECT_NE(r->warnings[0].find("times what the view asks for"), std::string::npos)
            << r->warnings[0];
      }
    }
  }
}

// The grid's outermost level (136 voxels, doubling per level) must stay where Embree takes rays.
TEST(HardInputs, GridVoxelIsBoundedByTheWorld) {
  GridOptions g;
  g.voxel = 1e13f;
  EXPECT_TRUE(grid::check_options(g).ok());
  g.voxel = 1e30f;
  expect_error(grid::check_options(g), "`grid.voxel`: ", "expected at most 1e+13");
}

// ---- Brightness (items 3 and 4): refused past floats, rendered exactly below. ----

// A floor under a sphere light, a sky and a sun, each light times 2^scale.
Scene lit_floor(int scale) {
  Scene s;
  s.camera = camera({0, 1.5f, 4}, {0, 0.3f, 0}, 12, 9);
  add_floor(s, 5, {0.6f, 0.6f, 0.6f});
  add_sphere(s, {0.4f, 0.8f, 0}, 0.3f, add_material(s, {0.5f, 0.5f, 0.5f}, {5, 4, 3}));
  testing::add_box(s, {-1.5f, 0, -0.5f}, {-0.8f, 0.7f, 0.2f}, add_material(s, {0.7f, 0.7f, 0.7f}));
  s.sky = {{0.2f, 0.3f, 0.6f}, {0.5f, 0.5f, 0.6f}, {0.1f, 0.1f, 0.1f}};
  s.has_sun = true;
  s.sun.direction = normalize(Vec3{0.4f, 1, 0.3f});
  s.sun.irradiance = {3, 2.5f, 2};
  for (Material& m : s.materials) m.emission = m.emission * std::ldexp(1.0f, scale);
  for (Rgb* c : {&s.sky.zenith, &s.sky.horizon, &s.sky.ground, &s.sun.irradiance})
    *c = *c * std::ldexp(1.0f, scale);
  return s;
}

// Before, spwi and the grid ended in "not finite ... a bug" on a sky of 3e37 and the path tracer
// drew an enclosure of 1e38 black at 8 bounces. A scene 2^k times brighter now renders to exactly
// 2^k times the image (rendered at 2^-k of its light when past 2^64, scaled back).
TEST(HardInputs, PowerOfTwoBrighterScenesRenderExactlyScaled) {
  for (Method m : {Method::pt, Method::spwi, Method::grid}) {
    RenderOptions o = testing::pt(2, 2);
    o.method = m;
    const ImageRgb base = testing::render_ok(lit_floor(0), o).radiance;
    ASSERT_GT(base.size(), 0u);
    for (int scale : {20, 70, 100}) {
      const ImageRgb bright = testing::render_ok(lit_floor(scale), o).radiance;
      ASSERT_EQ(bright.size(), base.size());
      std::size_t differ = 0;
      for (std::size_t i = 0; i < base.size(); ++i)
        differ += bright.data()[i] != std::ldexp(base.data()[i], scale);
      EXPECT_EQ(differ, 0u) << to_string(m) << " at 2^" << scale;
    }
  }
}

// The case: a sky of 3e37 over an open floor, a * 3e37 there (a uniform sky's irradiance is
// pi L), 3e37 where the camera sees the sky; spwi and the grid used to end in "not finite".
TEST(HardInputs, ASkyOf3e37RendersInEveryMethod) {
  Scene s;
  s.camera = camera({0, 1, 4}, {0, 0.8f, 0}, 8, 6);
  add_floor(s, 1e3f, {0.5f, 0.5f, 0.5f});
  s.sky = {{3e37f, 3e37f, 3e37f}, {3e37f, 3e37f, 3e37f}, {3e37f, 3e37f, 3e37f}};
  for (Method m : {Method::pt, Method::spwi, Method::grid}) {
    RenderOptions o = testing::pt(4, 2);
    o.method = m;
    const ImageRgb img = testing::render_ok(s, o).radiance;
    ASSERT_EQ(img.size(), 8u * 6 * 3) << to_string(m);
    EXPECT_FLOAT_EQ(img.data()[0], 3e37f) << to_string(m);  // the top left pixel sees the sky
    const float floor = img.data()[img.size() - 1];         // the bottom right sees the floor
    EXPECT_NEAR(floor / 1.5e37, 1, 0.05) << to_string(m);
  }
}

// An enclosure emitting Le with albedo 1 is Le (N + 1) at N bounces: 2e38 at one bounce fits a
// float and renders; at 8 bounces (9e38) it does not and is refused, naming the emission.
TEST(HardInputs, TooBrightIsRefusedNamingTheValueAndTheEdgeRenders) {
  Scene s;
  s.camera = camera({0.1f, -0.2f, 0.3f}, {0.5f, 0.4f, -1}, 6, 4, 90);
  testing::add_box(s, {-1, -1, -1}, {1, 1.5f, 2},
                   add_material(s, {1, 1, 1}, {1e38f, 1e38f, 1e38f}));
  s.source = "box.json";
  for (Method m : {Method::pt, Method::spwi, Method::grid}) {
    RenderOptions o = testing::pt(16, 1);
    o.method = m;
    EXPECT_TRUE(check_brightness(s, o).ok());
    const ImageRgb img = testing::render_ok(s, o).radiance;
    double sum = 0;
    for (std::size_t i = 0; i < img.size(); ++i) sum += img.data()[i];
    EXPECT_NEAR(sum / double(img.size()) / 2e38, 1, 0.02) << to_string(m);
    // At 2 bounces the answer, 3e38, fits; the path tracer's samples scatter about it and may
    // pass the float range: then refused, never an infinite pixel.
    o.bounces = 2;
    const Expected<RenderResult> near = render(s, o);
    if (near) {
      EXPECT_TRUE(all_finite(near->radiance)) << to_string(m);
    } else {
      EXPECT_EQ(m, Method::pt) << near.error().message;
      EXPECT_NE(near.error().message.find("passes the float range"), std::string::npos)
          << near.error().message;
    }
    o.bounces = 8;
    const std::string words =
        "1e+38 is too bright to render: with albedo up to 1 the radiance can reach 1e+38 x (1 + 1 "
        "+ "
        "... + 1^8) = 9e+38 at 8 bounces, more than a float holds (3.4e+38)";
    expect_error(check_brightness(s, o), "box.json: materials.m0.emission: ", words);
    const Expected<RenderResult> r = render(s, o);
    expect_error(r.ok() ? Status{} : Status{r.error()}, "box.json: materials.m0.emission: ", words);
  }
}

// The sun's disk has radiance E / (pi sin^2(angular radius)): past a float it is refused by name
// (it used to vanish, leaving the picture darker than with no sun); so is a bright sun's light.
TEST(HardInputs, ASunPastTheFloatsIsRefused) {
  Scene s = lit_floor(0);
  s.source = "sun.json";
  s.sun.angular_radius = 1e-20f;
  RenderOptions o = testing::pt(1, 1);
  expect_error(check_brightness(s, o), "sun.json: sun: ",
               "3 / (pi sin^2(1e-20 degrees)) = 3.13e+43, is more than a float holds");
  s.sun.angular_radius = 45;
  s.sun.irradiance = {3e38f, 1, 1};
  s.materials[2].albedo = {1, 1, 1};
  o.bounces = 8;
  expect_error(check_brightness(s, o), "sun.json: sun.irradiance: ", "from the sun");
  s.sun.irradiance = {1e30f, 1, 1};
  EXPECT_TRUE(check_brightness(s, o).ok());
  // A value that is not finite, in a scene built in code.
  s.sky.horizon.g = INFINITY;
  EXPECT_FALSE(render(s, o).ok());
}

}  // namespace
}  // namespace penumbra::spaceland
