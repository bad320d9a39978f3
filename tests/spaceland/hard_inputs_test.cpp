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

}  // namespace
}  // namespace penumbra::spaceland
