// The probe grid with fog and the sun, through render() against closed forms: an enclosure filled
// with fog that reflects and emits as its walls do gives Le (1 + a + ... + a^N); absorbing fog
// inside an emitting sphere (Beer-Lambert on the camera ray and on the light reaching the wall);
// a fog box lit by the sun (single scattering); the sun's light carried into the second bounce
// (a wall lit by a sunlit floor), by the grid and by SPWI through the grid's radiance cache; the
// same bits on any thread count.
#include <gtest/gtest.h>

#include <cmath>

#include "core/math.hpp"
#include "penumbra/spaceland/render.hpp"
#include "spaceland/camera.hpp"
#include "spaceland/color.hpp"
#include "spaceland/scene_builders.hpp"

namespace penumbra::spaceland {
namespace {

using namespace penumbra::spaceland::testing;

RenderOptions grid_options(float voxel, int bounces = 1) {
  RenderOptions o;
  o.method = Method::grid;
  o.grid.voxel = voxel;
  o.bounces = bounces;
  return o;
}

// The path tracer's fog-filled enclosure (scene_builders.hpp: furnace): every pixel is
// Le (1 + a + ... + a^N) at N bounces. The fog box covers part of the voxels it crosses (its
// faces lie off the voxel faces): extinction and emission scale together, so the answer holds
// there too.
TEST(GridFog, EnclosureFilledWithMatchingFogGivesTheGeometricSeries) {
  const Scene s = furnace(true, 24, 18);
  const Rgb le = s.materials[0].emission;
  const float a = s.materials[0].albedo.r;
  double want = 1, a_n = 1;
  for (int bounces = 1; bounces <= 4; ++bounces) {
    a_n *= a;
    want += a_n;
    const RenderResult r = render_ok(s, grid_options(0.06f, bounces));
    double worst = 0;
    for (int j = 0; j < 18; ++j)
      for (int i = 0; i < 24; ++i) {
        const Rgb got = r.radiance.at(i, j);
        worst = std::max(
            {worst, std::abs(got.r / (want * le.r) - 1), std::abs(got.b / (want * le.b) - 1)});
      }
    EXPECT_LT(worst, 0.01) << bounces << " bounces";
  }
}

// Absorbing grey fog inside an emitting sphere (scene_builders.hpp: absorbing_fog_sphere), one
// bounce: Beer-Lambert on the camera ray and on the light reaching the wall. The sphere's voxels
// stand in for its curved surface: measured within 3%.
TEST(GridFog, AbsorbingFogInsideAnEmittingSphereGivesBeerLambert) {
  FogSphere f = absorbing_fog_sphere();
  Scene& s = f.scene;
  const double want = f.want, le = 1, a = 0.8;
  const RenderResult got = render_ok(s, grid_options(0.05f));
  double mean = 0;
  for (int j = 0; j < 12; ++j)
    for (int i = 0; i < 16; ++i) {
      EXPECT_NEAR(got.radiance.at(i, j).r / want, 1.0, 0.05) << i << ", " << j;
      mean += got.radiance.at(i, j).r / (16 * 12);
    }
  EXPECT_NEAR(mean / want, 1.0, 0.03);
  // Without the fog the same pixels are Le + a Le: the fog's part is no accident.
  s.media.clear();
  EXPECT_NEAR(render_ok(s, grid_options(0.05f)).radiance.at(8, 6).r / (le * (1 + a)), 1.0, 0.03);
}

// A fog box alone under the sun straight above, no sky: the camera ray through it gathers
// sigma_s E / (4 pi) exp(-sigma (top - y)) from each point (the sun's path to the box's top),
// seen through exp(-sigma s) of the fog before it. Integrated here finely along each pixel's ray.
TEST(GridFog, SunlitFogScattersItsClosedForm) {
  Scene s;
  s.has_sun = true;
  s.sun.direction = {0, 1, 0};
  s.sun.irradiance = {3, 2, 1};
  s.sun.angular_radius = 0.5f;
  const float top = 1, depth = 2, sigma = 0.7f, albedo = 0.8f;
  Medium m;
  m.center = {0, 0, 0};
  m.half_size = {1.5f, top, depth / 2};
  m.extinction = {sigma, sigma, sigma};
  m.albedo = {albedo, albedo, albedo};
  s.media.push_back(m);
  const Vec3 eye{0.1f, -0.2f, 4};
  s.camera = camera(eye, {0.1f, -0.2f, 0}, 8, 6, 10);
  const RenderResult r = render_ok(s, grid_options(0.05f));
  const CameraRays rays(s.camera);
  for (int j = 0; j < 6; ++j)
    for (int i = 0; i < 8; ++i) {
      const Vec3 d = rays.direction(i, j);
      // The box's front and back faces, z = +-1 (the narrow view keeps every ray inside x, y).
      const double t_in = (eye.z - depth / 2) / -d.z, t_out = (eye.z + depth / 2) / -d.z;
      double want = 0;
      const int n = 20000;
      for (int k = 0; k < n; ++k) {
        const double t = t_in + (k + 0.5) * (t_out - t_in) / n;
        const double y = eye.y + d.y * t;
        want += std::exp(-sigma * (t - t_in)) * std::exp(-sigma * (top - y)) * (t_out - t_in) / n;
      }
      want *= sigma * albedo / (4 * kPi);
      const Rgb got = r.radiance.at(i, j);
      EXPECT_NEAR(got.r / (3 * want), 1.0, 0.005) << i << ", " << j;
      EXPECT_NEAR(got.b / (1 * want), 1.0, 0.005) << i << ", " << j;
    }
}

// A wall (x = 0, facing +x) on a floor (y = 0), both of albedo a, under the sun and a black sky.
// At two bounces a wall point shows a E cos_w / pi (the sun) plus a / pi times the irradiance the
// sunlit floor sends it: the floor's radiance L_f = a E cos_f / pi times pi F, F the view factor
// from the point to the floor, integrated here. The grid and SPWI (through the grid's radiance
// cache) both carry the sun into that bounce: the second bounce's light equals what each method
// gives at one bounce for a floor that emits L_f (to 2%), and the closed form to the methods' own
// error on this view (the grid's cascades 7.5% low, SPWI's 4.6% high, measured).
TEST(GridFog, TheSunReachesTheSecondBounce) {
  Scene s;
  s.has_sun = true;
  s.sun.direction = normalize(Vec3{0.6f, 0.7f, 0.39f});
  s.sun.irradiance = {3, 3, 3};
  s.sun.angular_radius = 0.5f;
  const float a = 0.5f, h = 1.0f, reach = 6, half = 3;
  add_box(s, {-0.2f, -0.2f, -half}, {0, 3, half}, add_material(s, {a, a, a}));  // the wall
  const std::uint32_t floor_material = add_material(s, {a, a, a});
  add_box(s, {-0.2f, -0.2f, -half}, {reach, 0, half}, floor_material);
  s.camera = camera({2, h, 0}, {0, h, 0}, 8, 8, 8);
  const Vec3 sun = normalize(s.sun.direction);
  const double e = 3, direct = a * e * sun.x / kPi, floor = a * e * sun.y / kPi;
  // F = int int x h / (pi r^4) dx dz over the floor [0, reach] x [-half, half].
  double f = 0;
  const int n = 1500;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k) {
      const double x = (i + 0.5) * reach / n, z = -half + (k + 0.5) * 2 * half / n;
      const double r2 = x * x + h * h + z * z;
      f += x * h / (kPi * r2 * r2) * (reach / n) * (2 * half / n);
    }
  const double bounce = a * floor * f;
  // The same view with no sun and the floor emitting L_f.
  Scene lamp = s;
  lamp.has_sun = false;
  lamp.materials[floor_material].emission = {float(floor), float(floor), float(floor)};
  for (Method method : {Method::grid, Method::spwi}) {
    RenderOptions o = grid_options(0.05f, 1);
    o.method = method;
    const double one = render_ok(s, o).radiance.at(4, 4).r;
    const double lit = render_ok(lamp, o).radiance.at(4, 4).r;
    o.bounces = 2;
    const double two = render_ok(s, o).radiance.at(4, 4).r;
    EXPECT_NEAR(one / direct, 1.0, 1e-4) << to_string(method);
    EXPECT_NEAR((two - one) / lit, 1.0, 0.02) << to_string(method);
    EXPECT_NEAR((two - one) / bounce, 1.0, 0.1) << to_string(method) << ": F = " << f;
  }
}

// Fog, the sun and a later bounce together: the same bits on 1 and 2 threads.
TEST(GridFog, SameBitsOnOneAndTwoThreads) {
  Scene s;
  s.has_sun = true;
  s.sun.direction = normalize(Vec3{0.5f, 1, 0.2f});
  s.sun.irradiance = {3, 3, 3};
  s.sky = {{0.2f, 0.3f, 0.5f}, {0.2f, 0.3f, 0.5f}, {0.2f, 0.3f, 0.5f}};
  add_box(s, {-2, -0.2f, -2}, {2, 0, 2}, add_material(s, {0.6f, 0.5f, 0.4f}));
  add_box(s, {-0.5f, 0, -0.5f}, {0.5f, 1, 0.5f}, add_material(s, {0.5f, 0.5f, 0.5f}));
  Medium m;
  m.center = {0, 1, 0};
  m.half_size = {2, 1, 2};
  m.extinction = {0.3f, 0.4f, 0.5f};
  m.albedo = {0.8f, 0.8f, 0.8f};
  s.media.push_back(m);
  s.camera = camera({3, 1.5f, 3}, {0, 0.5f, 0}, 24, 18, 60);
  const ImageRgb one = same_bits_on_one_and_two_threads(s, grid_options(0.1f, 2));
  EXPECT_GT(one.at(12, 9).r, 0.0f);
}

}  // namespace
}  // namespace penumbra::spaceland
