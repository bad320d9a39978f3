// The path tracer on glossy materials against closed forms and quadrature: a mirror floor shows
// Schlick's Fresnel times what its mirrored ray meets, exactly; a glossy floor under a uniform
// sky shows the sky times the BRDF's directional albedo; a rough metal floor under a sphere light
// shows the integral of the BRDF over the light (light sampling and BRDF sampling by MIS).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/brdf_reference.hpp"
#include "spaceland/scene_builders.hpp"

namespace penumbra::spaceland {
namespace {

using namespace penumbra::spaceland::testing;

Scene floor_scene(Rgb sky) {
  Scene s;
  s.camera = camera({0, 2, 4}, {0, 0, 0}, 32, 24, 50);
  s.sky = {sky, sky, sky};
  return s;
}

double schlick(double f0, double cos_t) {
  return f0 + (1 - f0) * std::pow(1 - cos_t, 5);
}

TEST(SpacelandPtGlossy, AMirrorFloorShowsFresnelTimesWhatItsMirroredRayMeets) {
  Scene s = floor_scene({0.5f, 0.5f, 0.5f});
  const int floor = add_glossy_floor(s, {0.9f, 0.6f, 0.3f}, 1, 0);
  const Sphere light =
      add_sphere(s, {0.2f, 1.2f, -2.5f}, 0.7f, add_material(s, {0, 0, 0}, {4, 3, 2}));
  const RenderResult r = render_ok(s, pt(4));
  const FirstHits hits = first_hits(s);
  int on_light = 0, on_sky = 0;
  double worst = 0;
  for (int j = 0; j < hits.position.height(); ++j)
    for (int i = 0; i < hits.position.width(); ++i) {
      if (int(hits.object.at(i, j).r) != floor) continue;
      const Rgb q = hits.position.at(i, j);
      const Vec3 p{q.r, q.g, q.b};
      const Vec3 wo = normalize(s.camera.position - p);
      const Vec3 d{-wo.x, wo.y, -wo.z};  // mirrored about the floor's normal (0, 1, 0)
      // The mirrored ray against the light: skip pixels at its rim, where rounding decides.
      const Vec3 oc = p - light.center;
      const double b = dot(oc, d), c = dot(oc, oc) - double(light.radius) * light.radius;
      const double disc = b * b - c;
      if (std::abs(disc) < 0.02) continue;
      const bool hits_light = disc > 0 && -b > 0;
      const Rgb seen = hits_light ? Rgb{4, 3, 2} : Rgb{0.5f, 0.5f, 0.5f};
      (hits_light ? on_light : on_sky) += 1;
      const double ct = wo.y;
      const Rgb got = r.radiance.at(i, j);
      worst = std::max({worst, std::abs(got.r / (schlick(0.9, ct) * seen.r) - 1),
                        std::abs(got.g / (schlick(0.6, ct) * seen.g) - 1),
                        std::abs(got.b / (schlick(0.3, ct) * seen.b) - 1)});
    }
  EXPECT_GT(on_light, 10);
  EXPECT_GT(on_sky, 200);
  EXPECT_LT(worst, 1e-4);
}

TEST(SpacelandPtGlossy, AGlossyFloorUnderAUniformSkyShowsItsDirectionalAlbedo) {
  for (const auto& [metallic, roughness] :
       {std::pair{0.0f, 0.3f}, std::pair{1.0f, 0.5f}, std::pair{0.5f, 0.8f},
        std::pair{0.0f, 0.0f}}) {  // the last: a mirror over a diffuse lobe (plastic)
    Scene s = floor_scene({1, 1, 1});
    const int floor = add_glossy_floor(s, {0.7f, 0.7f, 0.7f}, metallic, roughness);
    const AlbedoTable albedo(0.7, metallic, roughness);
    auto want = [&](Vec3, Vec3 wo) { return albedo(wo.y); };
    const auto [e64, mean64] = glossy_floor_error(s, render_ok(s, pt(64)).radiance, floor, want);
    const auto [e256, mean256] = glossy_floor_error(s, render_ok(s, pt(256)).radiance, floor, want);
    EXPECT_NEAR(mean256, 1.0, 0.003) << metallic << " " << roughness;
    EXPECT_LT(e256, 0.02) << metallic << " " << roughness;
    EXPECT_LT(e256, 0.6 * e64) << metallic << " " << roughness;
    (void)mean64;
  }
}

TEST(SpacelandPtGlossy, AGlossyFloorUnderASphereLightIntegratesTheBrdfOverTheLight) {
  const Vec3 n{0, 1, 0};
  // Rough metals, a glossy plastic (both lobes, one picked per sample: the mixture's density in
  // MIS) and a mirror plastic (the delta's weight F / p, and its mirrored ray meeting the light).
  for (const auto& [metallic, roughness] :
       {std::pair{1.0f, 0.15f}, std::pair{1.0f, 0.3f}, std::pair{1.0f, 0.6f}, std::pair{0.0f, 0.3f},
        std::pair{0.0f, 0.0f}}) {
    Scene s = floor_scene({0, 0, 0});
    const int floor = add_glossy_floor(s, {0.9f, 0.9f, 0.9f}, metallic, roughness);
    const float le = 5;
    const Sphere light =
        add_sphere(s, {0, 1.0f, -1.5f}, 0.3f, add_material(s, {0, 0, 0}, {le, le, le}));
    auto want = [&](Vec3 p, Vec3 wo) {
      const Vec3 to = light.center - p;
      const double d = length(to), sin_max = light.radius / d;
      const double width = 1 - std::sqrt(1 - sin_max * sin_max);
      double mirrored = 0;
      if (roughness == 0) {
        // The delta: Fresnel times the light where the mirrored ray meets it.
        const Vec3 m{-wo.x, wo.y, -wo.z};
        const Vec3 oc = p - light.center;
        const double b = dot(oc, m), c = dot(oc, oc) - double(light.radius) * light.radius;
        if (b * b - c > 0 && -b > 0) mirrored = reference_mirror(0.9, metallic, n, wo);
      }
      return le * (mirrored + cone_integral(to / float(d), width, [&](Vec3 wi) {
                     const double nl = dot(n, wi);
                     return nl > 0 ? reference_f(0.9, metallic, roughness, n, wo, wi) * nl : 0.0;
                   }));
    };
    const auto [e64, mean64] = glossy_floor_error(s, render_ok(s, pt(64)).radiance, floor, want);
    const auto [e256, mean256] = glossy_floor_error(s, render_ok(s, pt(256)).radiance, floor, want);
    EXPECT_NEAR(mean256, 1.0, 0.003) << metallic << " " << roughness;
    EXPECT_LT(e256, 0.01) << metallic << " " << roughness;
    // The mirror's delta is exact at any sample count: its floor of 0.1% (pixels whose mirrored
    // ray grazes the light's rim) is reached at 64 samples already.
    if (roughness > 0) {
      EXPECT_LT(e256, 0.6 * e64) << metallic << " " << roughness;
    }
    (void)mean64;
  }
}

}  // namespace
}  // namespace penumbra::spaceland
