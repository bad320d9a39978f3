// Screen-space radiance cascades against closed forms where they hold in screen space: a uniform
// sky over an open plane gives a L in every merge, sector count and bounce count; what is off
// screen gives nothing (the method's limitation, kept visible); the same bits on 1 and 2 threads
// and with 1, 2 or 4 directions marched together; the flatland layout; options refused where
// they make no sense; with --offscreen world an emitting enclosure is exact and a light behind
// the camera lights the floor; --merge fix stops all light at an infinitely thick wall. Three
// tests hold today's shortfalls to their measured size (docs/QUALITY.md): light under an
// on-screen wall, and a sphere light's pool (two).
#include "spaceland/ssrc/ssrc.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/scene_builders.hpp"

namespace penumbra::spaceland {
namespace {

using namespace penumbra::spaceland::testing;

constexpr double kPi = 3.14159265358979323846;

RenderOptions ssrc(int bounces = 1) {
  RenderOptions o;
  o.method = Method::ssrc;
  o.bounces = bounces;
  return o;
}

TEST(Ssrc, UniformSkyOverAnOpenPlaneIsALInEveryMergeGatherSectorCountAndBounce) {
  const Scene s = sky_plane();
  for (SpwiMerge m :
       {SpwiMerge::bilinear, SpwiMerge::bilateral, SpwiMerge::bilinear3d, SpwiMerge::fix})
    for (int sectors : {8, 16, 32})
      for (int bounces : {1, 2}) {
        RenderOptions o = ssrc(bounces);
        o.ssrc.merge = m;
        o.ssrc.sectors = sectors;
        o.ssrc.gather = sectors == 16 ? SpwiGather::pixel : SpwiGather::probe;
        const RenderResult r = render_ok(s, o);
        // Measured 0.17% to 1.0%: the pixel's view vector is not its probes' (their slices'
        // horizons differ), and a coarse texel's plane is clamped to [z/2, 2z].
        EXPECT_LT(sky_plane_error(r.radiance), 0.015)
            << to_string(m) << ", " << sectors << " sectors, " << bounces << " bounces, gather "
            << to_string(o.ssrc.gather);
      }
}

// Seen from above: a floor split by a wall taller than a small emitting box on one side. The
// wall's top is on screen, so the march meets it: the far side stays dark while the near side is
// lit (the control).
Scene walled_floor() {
  Scene s;
  s.camera = camera({0, 9, 0.01f}, {0, 0, 0}, 64, 64, 50);
  add_box(s, {-6, -1, -6}, {6, 0, 6}, add_material(s, {0.5f, 0.5f, 0.5f}));
  add_box(s, {-0.15f, 0, -6}, {0.15f, 1.5f, 6}, add_material(s, {0.5f, 0.5f, 0.5f}));
  add_box(s, {-1.6f, 0, -0.3f}, {-1.0f, 0.6f, 0.3f}, add_material(s, {0, 0, 0}, {20, 20, 20}));
  return s;
}

// The wall stops most of the light, more as it is thicker; measured (dark side's brightest over
// the lit side's mean) with the default merge: 0.36 at the default thickness (the wall's top is a
// slab 0.05 of its depth thick, and light passes under it), 0.24 with the back faces (the wall
// solid along each camera ray through it) and 0.13 infinitely thick (the merge hands a ray on to
// upper probes past the wall). With --merge fix each segment ends at its own upper probe's
// interval, so nothing is handed on past an infinitely thick wall (0.000); at the finite
// thicknesses the light passes under the slab as before (0.38, 0.23).
TEST(Ssrc, AnOnScreenWallStopsMostOfTheLightWhileTheLightsSideIsLit) {
  const Scene s = walled_floor();
  for (SpwiMerge m : {SpwiMerge::bilateral, SpwiMerge::fix})
    for (int model = 0; model < 3; ++model) {
      RenderOptions o = ssrc();
      o.ssrc.merge = m;
      o.ssrc.thickness = model == 2 ? 1e30f : 0.05f;
      o.ssrc.backfaces = model == 1;
      const char* const name[] = {"thickness 0.05", "back faces", "infinitely thick"};
      const RenderResult r = render_ok(s, o);
      const ImageRgb& img = r.radiance;
      // Floor pixels left of the light (lit) and right of the wall (dark), on the middle row.
      double lit = 0, dark = 0;
      for (int i = 2; i < 10; ++i) lit += img.at(i, 32).r;
      for (int i = 40; i < 62; ++i) dark = std::max(dark, double(img.at(i, 32).r));
      EXPECT_GT(lit / 8, 0.05) << name[model] << ": the light's side is not lit";
      std::printf("ssrc_test: wall, %s, merge %s: dark side over lit %.3f\n", name[model],
                  to_string(m), dark / (lit / 8));
      const double bound[2][3] = {{0.45, 0.3, 0.2}, {0.45, 0.3, 0.02}};
      EXPECT_LT(dark, bound[m == SpwiMerge::fix][model] * lit / 8)
          << name[model] << ", merge " << to_string(m) << ": more light passed the wall";
    }
}

// A sphere light (radius r, Le) over a grey floor, seen from above so that the light and the
// floor around it are on screen.
struct SphereOverFloor {
  Scene s;
  Vec3 c{0, 1, 0};
  float r = 0.25f;
  Rgb le{8, 6, 4};
  float a = 0.5f;
};
SphereOverFloor sphere_over_floor(int size) {
  SphereOverFloor f;
  f.s.camera = camera({0, 6, 3}, {0, 0, 0}, size, size, 50);
  add_floor(f.s, 100, {f.a, f.a, f.a});
  add_sphere(f.s, f.c, f.r, add_material(f.s, {0, 0, 0}, f.le));
  return f;
}

// Measured 0.39 relative RMSE against the aim of 0.1 (docs/QUALITY.md, "Screen-space
// cascades").
TEST(Ssrc, ASphereLightInViewLightsTheFloorNearItsClosedForm) {
  const SphereOverFloor f = sphere_over_floor(128);
  for (SpwiMerge m : {SpwiMerge::bilateral, SpwiMerge::fix}) {
    RenderOptions o = ssrc();
    o.ssrc.merge = m;
    const RenderResult r = render_ok(f.s, o);
    // The floor's points straight under the camera's rays: the closed form a Le (r/d)^2 cos for a
    // sphere light wholly above the horizon, on floor pixels between 1.2 and 3 units from the
    // light's foot (outside its own pixels and where the floor is lit well above the sky's zero).
    double sum_err = 0, sum_want = 0;
    int n = 0;
    const Vec3 eye = f.s.camera.position;
    for (int j = 0; j < 128; ++j)
      for (int i = 0; i < 128; ++i) {
        // The pixel's ray down to the floor.
        const double x = (2 * (i + 0.5) / 128 - 1) * std::tan(25 * kPi / 180);
        const double y = (1 - 2 * (j + 0.5) / 128) * std::tan(25 * kPi / 180);
        const Vec3 fwd = normalize(Vec3{0, 0, 0} - eye);
        const Vec3 right = normalize(cross(fwd, Vec3{0, 1, 0}));
        const Vec3 up = cross(right, fwd);
        const Vec3 d = normalize(fwd + right * float(x) + up * float(y));
        if (!(d.y < 0)) continue;
        const Vec3 p = eye + d * (-eye.y / d.y);
        const double foot = std::hypot(double(p.x - f.c.x), double(p.z - f.c.z));
        if (foot < 1.2 || foot > 3) continue;
        const Vec3 to = f.c - p;
        const double dist = length(to), cos_t = to.y / dist;
        const double want = f.a * f.le.r * (f.r / dist) * (f.r / dist) * cos_t;
        sum_err += std::pow(double(r.radiance.at(i, j).r) - want, 2);
        sum_want += want * want;
        ++n;
      }
    ASSERT_GT(n, 500);
    const double e = std::sqrt(sum_err / sum_want);
    std::printf("ssrc_test: sphere light's pool, merge %s, relative RMSE %.3f\n", to_string(m), e);
    EXPECT_LT(e, 0.5) << to_string(m);
  }
}

// The same light behind the camera: the path tracer's floor is lit, ssrc's is not (it sees only
// what is on screen; docs/QUALITY.md measures it).
TEST(Ssrc, ALightOffScreenGivesNothing) {
  Scene s;
  s.camera = camera({0, 2, 0}, {0, 0, -4}, 48, 36, 50);
  add_floor(s, 100, {0.5f, 0.5f, 0.5f});
  add_sphere(s, {0, 1, 2}, 0.4f, add_material(s, {0, 0, 0}, {20, 20, 20}));
  const RenderResult on = render_ok(s, pt(16)), off = render_ok(s, ssrc());
  double reference = 0, got = 0;
  for (int j = 20; j < 36; ++j)
    for (int i = 0; i < 48; ++i) {
      reference += on.radiance.at(i, j).r;
      got += off.radiance.at(i, j).r;
    }
  EXPECT_GT(reference, 1.0);
  EXPECT_EQ(got, 0.0);
}

RenderOptions ssrc_world(int bounces = 1) {
  RenderOptions o = ssrc(bounces);
  o.ssrc.offscreen = SsrcOffscreen::world;
  return o;
}

// --offscreen world: inside an enclosure whose walls all emit Le and reflect a, what leaves the
// screen meets a wall as what stays on it does, and every pixel is Le (1 + a) at one bounce and
// Le (1 + a + a^2) at two (the last bounce's rays off screen read the radiance cache) exactly;
// seeing the sky instead, the pixels near the screen's edges lose most of a Le. (At three
// bounces it is 1.3% short: the second bounce's rays off screen see the emission alone.)
TEST(Ssrc, OffScreenRaysThroughTheWorldMakeAnEmittingEnclosureExact) {
  for (int bounces : {1, 2}) {
    const Scene s = furnace(false, 48, 36);
    const Rgb le{1.0f, 0.5f, 0.25f};
    const double a = 0.6, sum = bounces == 1 ? 1 + a : 1 + a + a * a;
    const RenderResult world = render_ok(s, ssrc_world(bounces)), sky = render_ok(s, ssrc(bounces));
    const auto channel = [](Rgb v, int c) { return double(c == 0 ? v.r : c == 1 ? v.g : v.b); };
    double worst = 0, worst_sky = 0;
    for (int j = 0; j < 36; ++j)
      for (int i = 0; i < 48; ++i)
        for (int c = 0; c < 3; ++c) {
          const double want = channel(le, c) * sum;
          worst = std::max(worst, std::abs(channel(world.radiance.at(i, j), c) / want - 1));
          worst_sky = std::max(worst_sky, std::abs(channel(sky.radiance.at(i, j), c) / want - 1));
        }
    EXPECT_LT(worst, 2e-3);  // measured 6e-4: float sums over the sectors
    EXPECT_GT(worst_sky, 0.2);
    EXPECT_GT(world.rays, 0u);
  }
}

// A sphere light behind the camera over a wide floor: with --offscreen world the floor's pool
// follows a Le (r/d)^2 cos, measured 0.55 relative RMSE. The same light in view, marched on
// screen, is held to its measured shortfall (1.40 at thickness 0.05; 0.65 at 0; 0.38 with one
// cascade of 64 directions: the merges' parallax and the slab model, issue 38's open items,
// docs/QUALITY.md).
TEST(Ssrc, OffScreenRaysThroughTheWorldLightTheFloorFromBehindTheCamera) {
  const double behind = wide_floor_error(ssrc_world(), true);
  const double in_view = wide_floor_error(ssrc_world(), false);
  std::printf("ssrc_test: --offscreen world, light behind %.3f, in view %.3f\n", behind, in_view);
  EXPECT_LT(behind, 0.7);
  EXPECT_LT(in_view, 1.6);
}

bool same_bits(const ImageRgb& a, const ImageRgb& b) {
  return a.width() == b.width() && a.height() == b.height() &&
         std::memcmp(a.data(), b.data(),
                     sizeof(float) * 3 * std::size_t(a.width()) * std::size_t(a.height())) == 0;
}

TEST(Ssrc, SameBitsOnOneAndTwoThreadsAndWithOneTwoOrFourDirectionsMarchedTogether) {
  const SphereOverFloor f = sphere_over_floor(64);
  RenderOptions o = ssrc(2);
  const ImageRgb four = same_bits_on_one_and_two_threads(f.s, o);
  for (int rays : {1, 2}) {
    o.ssrc.rays = rays;
    EXPECT_TRUE(same_bits(render_ok(f.s, o).radiance, four)) << rays << " directions together";
  }
  // The fix's segments to the upper probes share the lanes instead.
  o = ssrc(2);
  o.ssrc.merge = SpwiMerge::fix;
  same_bits_on_one_and_two_threads(f.s, o);
}

TEST(Ssrc, TheLayoutFollowsTheFlatlandLaw) {
  SsrcOptions o;
  const ssrc::Layout l = ssrc::make_layout(640, 480, o);
  EXPECT_EQ(l.tiles.spacing(0), kSpwiSpacing);
  EXPECT_EQ(l.r0, 4 * kSpwiSpacing);
  for (int i = 0; i < l.count(); ++i) {
    EXPECT_EQ(l.tiles.spacing(i), kSpwiSpacing << i);
    EXPECT_EQ(l.directions(i), o.directions << i);
    EXPECT_EQ(l.start(i), i == 0 ? 0.0 : l.r0 * double(1 << (i - 1)));
  }
  // The last interval is the first to reach across the diagonal (800 pixels).
  EXPECT_GE(l.end(l.count() - 1), 800);
  EXPECT_LT(l.end(l.count() - 2), 800);
  // Each cascade holds half the values of the one below (a quarter of the probes, twice the
  // directions), up to the tiles' rounding.
  for (int i = 1; i < l.count() - 2; ++i)
    EXPECT_NEAR(double(l.values(i)) / double(l.values(i - 1)), 0.5, 0.1);
}

TEST(Ssrc, RefusesWhatItCannotDo) {
  const Scene plane = sky_plane();
  auto refused = [&](const Scene& s, RenderOptions o, const std::string& names) {
    const Expected<RenderResult> r = render(s, o);
    ASSERT_FALSE(r) << names;
    EXPECT_NE(r.error().message.find(names), std::string::npos) << r.error().message;
  };
  RenderOptions o = ssrc();
  o.ssrc.sectors = 12;
  refused(plane, o, "`ssrc.sectors`");
  o = ssrc();
  o.ssrc.rays = 3;
  refused(plane, o, "`ssrc.rays`");
  o = ssrc();
  o.ssrc.directions = 6;
  refused(plane, o, "`ssrc.directions`");
  o.ssrc.directions = 2 * ssrc::kMaxDirections;
  refused(plane, o, "`ssrc.directions`");
  o = ssrc();
  o.ssrc.thickness = -1;
  refused(plane, o, "`ssrc.thickness`");
  o = ssrc();
  o.ssrc.merge = SpwiMerge::minmax;
  refused(plane, o, "`ssrc.merge`");
  o = ssrc();
  o.ssrc.interval = -2;
  refused(plane, o, "`ssrc.interval`");
  Scene fog = plane;
  Medium m;
  m.extinction = {1, 1, 1};
  fog.media.push_back(m);
  refused(fog, ssrc(), "fog");
  o = ssrc();
  o.max_memory = 1 << 16;
  refused(plane, o, "max_memory");
}

}  // namespace
}  // namespace penumbra::spaceland
