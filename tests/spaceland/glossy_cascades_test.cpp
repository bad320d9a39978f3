// Glossy materials through the cascade methods that read a specular lobe (SPWI's cone queries,
// the probe grid's widest query) against closed forms: a uniform sky gives the directional
// albedo, the sun's highlight is f cos E, and a rough floor under a sphere light is the BRDF
// integrated over the light's cone (the same truth the path tracer is held to).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>

#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/brdf_reference.hpp"
#include "spaceland/scene_builders.hpp"

namespace penumbra::spaceland {
namespace {

using namespace penumbra::spaceland::testing;

RenderOptions method(Method m) {
  RenderOptions o;
  o.method = m;
  return o;
}

// Under a uniform sky any normalised average of the cascades is the sky, so the floor is the sky
// times the BRDF's directional albedo, to the split-sum tables' 0.5%, at any roughness (the
// grid's mirror read as wide as a cell; SPWI's every query and merge mode: spwi_test.cpp).
TEST(GlossyCascades, GlossyFloorsUnderAUniformSkyGiveTheirDirectionalAlbedo) {
  for (Method m : {Method::spwi, Method::grid})
    for (const auto& [metallic, roughness] : {std::pair{0.0f, 0.3f}, std::pair{1.0f, 0.5f},
                                              std::pair{1.0f, 0.0f}, std::pair{0.5f, 1.0f}}) {
      Scene s;
      s.camera = camera({0, 2, 4}, {0, 0, 0}, 48, 36, 50);
      s.sky = {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
      const int floor = add_glossy_floor(s, {0.7f, 0.7f, 0.7f}, metallic, roughness);
      const AlbedoTable albedo(0.7, metallic, roughness);
      const auto [error, mean] = glossy_floor_error(s, render_ok(s, method(m)).radiance, floor,
                                                    [&](Vec3, Vec3 wo) { return albedo(wo.y); });
      EXPECT_LT(error, 0.006) << to_string(m) << " " << metallic << " " << roughness;
      EXPECT_NEAR(mean, 1, 0.004) << to_string(m) << " " << metallic << " " << roughness;
    }
}

// The sun on a glossy floor: the BRDF towards the sun's centre times its irradiance and cosine.
TEST(GlossyCascades, TheSunOnAGlossyFloorIsTheBrdfTimesItsIrradiance) {
  for (Method m : {Method::spwi, Method::grid})
    for (const auto& [metallic, roughness] : {std::pair{1.0f, 0.4f}, std::pair{0.0f, 0.6f}}) {
      Scene s;
      s.camera = camera({0, 2, 4}, {0, 0, 0}, 48, 36, 50);
      s.has_sun = true;
      s.sun.direction = normalize(Vec3{0, 1, -1.6f});
      s.sun.irradiance = {2, 2, 2};
      const int floor = add_glossy_floor(s, {0.7f, 0.7f, 0.7f}, metallic, roughness);
      const Vec3 n{0, 1, 0};
      const auto [error, mean] =
          glossy_floor_error(s, render_ok(s, method(m)).radiance, floor, [&](Vec3, Vec3 wo) {
            return 2 * reference_f(0.7, metallic, roughness, n, wo, s.sun.direction) *
                   dot(n, s.sun.direction);
          });
      EXPECT_LT(error, 1e-3) << to_string(m) << " " << metallic << " " << roughness;
      EXPECT_NEAR(mean, 1, 1e-3) << to_string(m) << " " << metallic << " " << roughness;
    }
}

// A rough floor under a sphere light (radius 0.3, 1 above the floor), black sky, one bounce:
// each pixel is Le times the BRDF's cosine-weighted integral over the light's cone. Lobes at
// least as wide as the cascades' cells (roughness 0.6 and 1 against SPWI's cascade 0, 0.7 and 1
// against the grid's 16 directions), so that neither blurs the lobe itself; the light's share is
// spread over cells (SPWI) or met at the point and weighted by the lobe towards its centre (the
// grid's cascade 0).
TEST(GlossyCascades, ARoughFloorUnderASphereLightIsTheBrdfOverTheLight) {
  struct Case {
    Method m;
    float metallic, roughness;
    double error, mean;  // the bounds: relative RMSE over the floor, and the mean's ratio
  };
  // The bounds: measured (2026-11-29, 64 x 48) with a margin. SPWI's rough metal at 0.6 is 13%
  // dark under the light (its cone to cascade 1, the light spread over cascade 0's cells:
  // docs/QUALITY.md, "Glossy materials"), 99% of the floor's mean; at 1 (the widest query) and
  // its plastic, within 14%. The grid's lobes over its 16 cells: its metal 25% and 21% (too
  // bright under the light at 0.7, too dark around it at 1), its plastic 4%.
  for (const Case& c :
       {Case{Method::spwi, 1, 0.6f, 1.1, 0.18}, Case{Method::spwi, 1, 1, 0.13, 0.04},
        Case{Method::spwi, 0, 0.6f, 0.16, 0.03}, Case{Method::grid, 1, 0.7f, 0.3, 0.05},
        Case{Method::grid, 1, 1, 0.25, 0.14}, Case{Method::grid, 0, 0.7f, 0.06, 0.02}}) {
    Scene s;
    s.camera = camera({0, 2, 4}, {0, 0, 0}, 64, 48, 50);
    const int floor = add_glossy_floor(s, {0.9f, 0.9f, 0.9f}, c.metallic, c.roughness);
    const float le = 5;
    const Sphere light =
        add_sphere(s, {0, 1.0f, -1.5f}, 0.3f, add_material(s, {0, 0, 0}, {le, le, le}));
    const Vec3 n{0, 1, 0};
    auto want = [&](Vec3 p, Vec3 wo) {
      const Vec3 to = light.center - p;
      const double d = length(to), sin_max = light.radius / d;
      return le * cone_integral(to / float(d), 1 - std::sqrt(1 - sin_max * sin_max), [&](Vec3 wi) {
               const double nl = dot(n, wi);
               return nl > 0 ? reference_f(0.9, c.metallic, c.roughness, n, wo, wi) * nl : 0.0;
             });
    };
    // Relative to the floor's mean: the far floor, where the light's share is small, weighs by
    // its light.
    const auto [error, mean] =
        glossy_floor_error(s, render_ok(s, method(c.m)).radiance, floor, want, Relative::mean);
    EXPECT_LT(error, c.error) << to_string(c.m) << " " << c.metallic << " " << c.roughness;
    EXPECT_NEAR(mean, 1, c.mean) << to_string(c.m) << " " << c.metallic << " " << c.roughness;
  }
}

// Glossy pixels keep per-thread scratch (the lobe's weights and cells): the image is the same on
// any thread count, through SPWI's cone (to cascade 3 at roughness 0.3, the top for the mirror)
// and the grid's lobe.
TEST(GlossyCascades, SameBitsOnOneAndTwoThreads) {
  for (const float roughness : {0.3f, 0.0f}) {
    Scene s;
    s.camera = camera({0.3f, 2, 3}, {0, 0, -1}, 64, 48, 60);
    s.sky = {{1.5f, 1, 0.5f}, {1.5f, 1, 0.5f}, {1.5f, 1, 0.5f}};
    add_floor(s, 3, {0.6f, 0.6f, 0.6f});  // small: few voxels for the grid
    Material& plane = s.materials[s.disks.front().material];
    plane.metallic = 1;
    plane.roughness = roughness;
    add_sphere(s, {0, 0.5f, -1}, 0.5f, add_material(s, {0.3f, 0.8f, 0.3f}, {1, 0, 0}));
    for (Method m : {Method::spwi, Method::grid}) {
      SCOPED_TRACE(std::string(to_string(m)) + " " + std::to_string(roughness));
      same_bits_on_one_and_two_threads(s, method(m));
    }
  }
}

}  // namespace
}  // namespace penumbra::spaceland
