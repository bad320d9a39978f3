// The 3D path tracer against closed forms: enclosures (with and without fog), a sphere light
// over a plane, a sky occluded by a black sphere, the sun and its hard shadow, Beer-Lambert and
// fog emission; convergence; the same bits on any number of threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/scene_builders.hpp"

namespace penumbra::spaceland {
namespace {

using namespace penumbra::spaceland::testing;

constexpr double kPi = std::numbers::pi;

double geometric_sum(double a, int n) {
  double s = 0, p = 1;
  for (int k = 0; k <= n; ++k, p *= a) s += p;
  return s;
}

void expect_furnace(bool fog, int spp, double tolerance) {
  const Scene s = furnace(fog, 12, 9);
  const Rgb le = s.materials[0].emission;
  for (int n = 1; n <= 4; ++n) {
    const RenderResult r = render_ok(s, pt(spp, n));
    const double expect = geometric_sum(0.6, n);
    double mean[3] = {0, 0, 0}, worst = 0;
    const int pixels = r.radiance.width() * r.radiance.height();
    for (int k = 0; k < pixels; ++k)
      for (int c = 0; c < 3; ++c) {
        const double want = expect * (c == 0 ? le.r : c == 1 ? le.g : le.b);
        const double got = r.radiance.data()[3 * k + c];
        mean[c] += got / pixels;
        worst = std::max(worst, std::abs(got / want - 1));
      }
    for (int c = 0; c < 3; ++c) {
      const double want = expect * (c == 0 ? le.r : c == 1 ? le.g : le.b);
      EXPECT_NEAR(mean[c] / want, 1.0, tolerance) << "bounces " << n << " channel " << c;
    }
    EXPECT_LT(worst, 10 * tolerance) << "bounces " << n;
  }
}

TEST(SpacelandPt, EnclosureGivesTheGeometricSeriesOfItsAlbedo) {
  expect_furnace(false, 64, 0.003);
}

TEST(SpacelandPt, EnclosureFilledWithMatchingFogGivesTheSameSeries) {
  expect_furnace(true, 256, 0.01);
}

// A plane of albedo a (a large disk at y = 0) under an emitting sphere; the camera looks down.
Scene sphere_light_scene(Rgb sky) {
  Scene s;
  s.camera = camera({0, 3, 4}, {0, 0, 0}, 32, 24, 50);
  s.sky = {sky, sky, sky};
  add_floor(s, 1000, {0.5f, 0.5f, 0.5f});
  return s;
}

TEST(SpacelandPt, SphereLightOverAPlaneGivesALeRSquaredCosOverDSquared) {
  Scene s = sphere_light_scene({0, 0, 0});
  const Sphere light = add_sphere(s, {0.3f, 2, -0.5f}, 0.5f, add_material(s, {0, 0, 0}, {4, 3, 2}));
  const RenderResult r = render_ok(s, pt(64));
  const FirstHits hits = first_hits(s);
  const ImageRgb &pos = hits.position, &obj = hits.object;
  int tested = 0;
  double worst = 0;
  for (int j = 0; j < pos.height(); ++j)
    for (int i = 0; i < pos.width(); ++i) {
      if (obj.at(i, j).r != 0) continue;  // the light itself
      const Rgb p = pos.at(i, j);
      const double dx = light.center.x - p.r, dy = light.center.y - p.g, dz = light.center.z - p.b;
      const double d2 = dx * dx + dy * dy + dz * dz;
      const double cos_t = dy / std::sqrt(d2);
      const double k = 0.5 * light.radius * light.radius / d2 * cos_t;
      const Rgb got = r.radiance.at(i, j);
      worst = std::max({worst, std::abs(got.r / (4 * k) - 1), std::abs(got.g / (3 * k) - 1),
                        std::abs(got.b / (2 * k) - 1)});
      ++tested;
    }
  EXPECT_GT(tested, 600);
  EXPECT_LT(worst, 0.01);
}

TEST(SpacelandPt, UniformSkyOverAPlaneLosesTheCapABlackSphereHides) {
  const float sky = 2;
  Scene s = sphere_light_scene({sky, sky, sky});
  const Sphere blocker = add_sphere(s, {0.3f, 1.5f, -0.5f}, 0.5f, add_material(s, {0, 0, 0}));
  const FirstHits hits = first_hits(s);
  const ImageRgb &pos = hits.position, &obj = hits.object;
  // Relative RMS error over the plane's pixels at n samples.
  auto error_at = [&](int spp) {
    const RenderResult r = render_ok(s, pt(spp));
    double sum = 0, mean_got = 0, mean_want = 0;
    int n = 0;
    for (int j = 0; j < pos.height(); ++j)
      for (int i = 0; i < pos.width(); ++i) {
        if (obj.at(i, j).r != 0) continue;
        const Rgb p = pos.at(i, j);
        const double dx = blocker.center.x - p.r, dy = blocker.center.y - p.g,
                     dz = blocker.center.z - p.b;
        const double d2 = dx * dx + dy * dy + dz * dz;
        const double want =
            0.5 * sky * (1 - blocker.radius * blocker.radius / d2 * (dy / std::sqrt(d2)));
        const double got = r.radiance.at(i, j).g;
        sum += (got / want - 1) * (got / want - 1);
        mean_got += got;
        mean_want += want;
        ++n;
      }
    EXPECT_NEAR(mean_got / mean_want, 1.0, 0.003) << spp << " spp";
    return std::sqrt(sum / n);
  };
  const double e16 = error_at(16), e64 = error_at(64), e256 = error_at(256);
  // Four times the samples at least halve the error (Owen-scrambled Sobol points do better).
  EXPECT_LT(e64, 0.55 * e16);
  EXPECT_LT(e256, 0.55 * e64);
  EXPECT_LT(e256, 0.01);
}

TEST(SpacelandPt, SunOnAPlaneGivesAECosOverPiAndNothingInTheHardShadow) {
  Scene s = sphere_light_scene({0, 0, 0});
  s.camera.width = 64;  // enough pixels inside the shadow
  s.camera.height = 48;
  s.has_sun = true;
  s.sun.direction = normalize(Vec3{0.3f, 1, 0.2f});
  s.sun.irradiance = {3, 2, 1};
  Disk blocker;
  blocker.center = {0, 1, 0};
  blocker.radius = 0.6f;
  blocker.material = add_material(s, {0, 0, 0});
  blocker.object = add_object(s, "disk");
  s.disks.push_back(blocker);
  const RenderResult r = render_ok(s, pt(16));
  const FirstHits hits = first_hits(s);
  const ImageRgb &pos = hits.position, &obj = hits.object;
  const Vec3 sun = s.sun.direction;
  const double lit = 0.5 * sun.y / kPi;  // a E cos(theta) / pi per unit of irradiance
  int in_shadow = 0, in_light = 0;
  for (int j = 0; j < pos.height(); ++j)
    for (int i = 0; i < pos.width(); ++i) {
      if (obj.at(i, j).r != 0) continue;
      const Rgb p = pos.at(i, j);
      // Where the ray towards the sun's centre crosses the blocker's plane (y = 1).
      const double t = (1 - p.g) / sun.y;
      const double hx = p.r + t * sun.x, hz = p.b + t * sun.z;
      const double rho = std::sqrt(hx * hx + hz * hz);
      const Rgb got = r.radiance.at(i, j);
      // Clear of the penumbra (0.27 degrees, under 0.01 wide here) by a margin.
      if (rho < blocker.radius - 0.03) {
        EXPECT_EQ(got.r + got.g + got.b, 0.0f) << i << ", " << j;
        ++in_shadow;
      } else if (rho > blocker.radius + 0.03) {
        EXPECT_NEAR(got.r / (3 * lit), 1.0, 1e-3) << i << ", " << j;
        EXPECT_NEAR(got.b / (1 * lit), 1.0, 1e-3) << i << ", " << j;
        ++in_light;
      }
    }
  EXPECT_GT(in_shadow, 20);
  EXPECT_GT(in_light, 1200);
}

// One pixel looking along -z at an emitting wall through a slab of fog.
Scene slab(Rgb extinction, Rgb emission, Rgb wall) {
  Scene s;
  s.camera = camera({0, 0, 0}, {0, 0, -1}, 1, 1, 10);
  Disk w;
  w.center = {0, 0, -3};
  w.normal = {0, 0, 1};
  w.radius = 10;
  w.material = add_material(s, {0, 0, 0}, wall);
  w.object = add_object(s, "disk");
  s.disks.push_back(w);
  Medium m;
  m.center = {0, 0, -1.5f};
  m.half_size = {5, 5, 0.5f};
  m.extinction = extinction;
  m.albedo = {0, 0, 0};
  m.emission = emission;
  s.media.push_back(m);
  return s;
}

TEST(SpacelandPt, FogAttenuatesAsBeerLambert) {
  const Rgb sigma{0.5f, 1.0f, 2.0f};
  const int spp = 4096;
  const RenderResult r = render_ok(slab(sigma, {}, {2, 2, 2}), pt(spp));
  const Rgb got = r.radiance.at(0, 0);
  // Each sample passes (weight T / P) or is absorbed: a Bernoulli estimate with P the mean
  // transmittance; allow four standard errors.
  const double t[3] = {std::exp(-0.5), std::exp(-1.0), std::exp(-2.0)};
  const double p = (t[0] + t[1] + t[2]) / 3;
  const double tol = 4 * std::sqrt((1 - p) / (p * spp));
  EXPECT_NEAR(got.r / (2 * t[0]), 1.0, tol);
  EXPECT_NEAR(got.g / (2 * t[1]), 1.0, tol);
  EXPECT_NEAR(got.b / (2 * t[2]), 1.0, tol);
}

TEST(SpacelandPt, EmittingFogGivesItsClosedForm) {
  const Rgb sigma{0.5f, 1.0f, 2.0f}, e{1, 2, 3};
  const RenderResult r = render_ok(slab(sigma, e, {}), pt(4));
  const Rgb got = r.radiance.at(0, 0);
  EXPECT_NEAR(got.r, 1 * (1 - std::exp(-0.5)) / 0.5, 1e-5);
  EXPECT_NEAR(got.g, 2 * (1 - std::exp(-1.0)) / 1.0, 1e-5);
  EXPECT_NEAR(got.b, 3 * (1 - std::exp(-2.0)) / 2.0, 1e-5);
}

TEST(SpacelandPt, SameBitsOnOneAndTwoThreadsAndDependsOnTheSeed) {
  Scene s = furnace(true, 12, 9);
  s.has_sun = true;
  s.sun.irradiance = {1, 1, 1};
  RenderOptions o = pt(8, 3);
  const ImageRgb one = same_bits_on_one_and_two_threads(s, o);
  o.pt.seed = 7;
  const ImageRgb other = render_ok(s, o).radiance;
  EXPECT_FALSE(std::equal(one.data(), one.data() + one.size(), other.data()));
}

TEST(SpacelandPt, CancelStopsAfterAPassWithTheSamplesSoFar) {
  const Scene s = furnace(false, 12, 9);
  std::atomic<bool> cancel{true};
  RenderOptions o = pt(1000);
  o.cancel = &cancel;
  const RenderResult r = render_ok(s, o);
  EXPECT_TRUE(r.cancelled);
  EXPECT_EQ(r.samples, 1u);
  EXPECT_GT(r.radiance.at(0, 0).r, 0.0f);
}

TEST(SpacelandPt, RefusesBadOptionsAndWorkPastTheMemoryLimit) {
  const Scene s = furnace(false, 12, 9);
  RenderOptions o = pt(0);
  Expected<RenderResult> r = render(s, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("pt.spp"), std::string::npos) << r.error().message;
  o = pt(4);
  o.bounces = 0;
  r = render(s, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("bounces"), std::string::npos) << r.error().message;
  o = pt(4);
  o.max_memory = 1000;
  r = render(s, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("max_memory"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace penumbra::spaceland
