// Glossy materials through the cascade methods that read a specular lobe (SPWI's and the probe
// grid's cone queries, ssrc's and the surface cascades' widest queries) against closed forms: a
// uniform sky gives the directional albedo, the sun's highlight is f cos E, and a rough floor under
// a sphere light is the BRDF integrated over the light's cone (the same truth the path tracer is
// held to).
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
  for (Method m : {Method::spwi, Method::grid, Method::ssrc, Method::surface})
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
  for (Method m : {Method::spwi, Method::grid, Method::ssrc, Method::surface})
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
  // its plastic, within 14%. The grid meets this light at the point, its share of the lobe
  // taken over its cap (cascade::lobe_share): its metal 7.3%, 0.69% and 0.27% at 0.3, 0.7 and
  // 1, its plastic 11.6% and 3.0% at 0.3 and 0.7 (the diffuse gather's error); every mean
  // within 0.8%. (Over its 16 cells, before: its metal 25% at 0.7 and 21% at 1.) The surface
  // cascades' widest query (2026-11-30): metal 92% at 0.6 and 83% of the mean (the bake spreads
  // the light over cascade 0's 30-degree cells, wider than this lobe), 11% and 0.93 at 1; its
  // plastic 7.4% and 0.99. ssrc is left out: its diffuse gather alone is 2.15x this floor's
  // light (a Lambertian floor: 3.4 relative RMSE), the small sphere light's known limit on
  // screen (docs/QUALITY.md, "Screen-space cascades").
  for (const Case& c :
       {Case{Method::spwi, 1, 0.6f, 1.1, 0.18}, Case{Method::spwi, 1, 1, 0.13, 0.04},
        Case{Method::spwi, 0, 0.6f, 0.16, 0.03}, Case{Method::grid, 1, 0.3f, 0.1, 0.01},
        Case{Method::grid, 1, 0.7f, 0.015, 0.005}, Case{Method::grid, 1, 1, 0.01, 0.005},
        Case{Method::grid, 0, 0.3f, 0.15, 0.015}, Case{Method::grid, 0, 0.7f, 0.045, 0.008},
        Case{Method::surface, 1, 0.6f, 0.96, 0.2}, Case{Method::surface, 1, 1, 0.13, 0.08},
        Case{Method::surface, 0, 0.6f, 0.09, 0.015}}) {
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
    for (Method m : {Method::spwi, Method::grid, Method::ssrc, Method::surface}) {
      SCOPED_TRACE(std::string(to_string(m)) + " " + std::to_string(roughness));
      same_bits_on_one_and_two_threads(s, method(m));
    }
  }
}

// A mirror floor reflecting a small sphere light over a black sky: where the mirrored view meets
// the light, Schlick's F times its radiance, elsewhere nothing. The grid meets a light this small
// at the point (lights_at) and takes the part of the lobe inside its cap (lobe_share: for a
// mirror, all or none), as sharp as the exact ray.
TEST(GlossyCascades, ASmallLightInTheGridsMirrorIsSchlickTimesItsRadiance) {
  Scene s;
  s.camera = camera({0, 1.2f, 3}, {0, 0, -1}, 96, 72, 50);
  const int floor = add_glossy_floor(s, {0.9f, 0.9f, 0.9f}, 1, 0);
  const Vec3 centre{0.2f, 0.6f, -2};
  const float radius = 0.15f, le = 40;
  add_sphere(s, centre, radius, add_material(s, {0, 0, 0}, {le, le, le}));
  const auto [error, mean] = glossy_floor_error(
      s, render_ok(s, method(Method::grid)).radiance, floor,
      [&](Vec3 p, Vec3 wo) {
        const Vec3 r{-wo.x, wo.y, -wo.z};  // wo mirrored about the floor's normal (0, 1, 0)
        const Vec3 to = centre - p;
        const float along = dot(to, r);
        const bool hit = along > 0 && dot(to, to) - along * along < radius * radius;
        return hit ? reference_mirror(0.9, 1, {0, 1, 0}, wo) * le : 0.0;
      },
      Relative::mean);
  // Measured (2026-11-29): 0.12% (a pixel or two on the reflection's rim), the mean to 5e-5.
  EXPECT_LT(error, 0.005);
  EXPECT_NEAR(mean, 1, 0.001);
}

// A metal floor (albedo 0.9) of the given roughness under a sky from a black horizon to a white
// zenith (L = w.y), 48 x 36: the floor's error against the BRDF integrated against that sky.
struct GradientFloor {
  Scene s;
  int floor = 0;
  float roughness = 0;
  explicit GradientFloor(float r) : roughness(r) {
    s.camera = camera({0, 2, 4}, {0, 0, 0}, 48, 36, 50);
    s.sky = {{1, 1, 1}, {0, 0, 0}, {0, 0, 0}};
    floor = add_glossy_floor(s, {0.9f, 0.9f, 0.9f}, 1, roughness);
  }
  double want(Vec3 wo) const {
    const Vec3 n{0, 1, 0};
    auto f = [&](Vec3 wi) {
      return wi.y > 0 ? reference_f(0.9, 1, roughness, n, wo, wi) * wi.y * wi.y : 0.0;
    };
    // Below 0.5: over 60 degrees about the mirror direction, the lobe's tail past it under
    // 1e-3 at 0.3; above: over the hemisphere (its tail reaches past 90 degrees).
    const Vec3 r{-wo.x, wo.y, -wo.z};
    return roughness < 0.5f ? cone_integral(r, 0.5, f, 200, 100) : cone_integral(n, 1, f, 200, 200);
  }
  // Relative RMSE over the floor and the mean's ratio (glossy_floor_error, relative to the mean).
  std::pair<double, double> error(const RenderOptions& o) const {
    return glossy_floor_error(
        s, render_ok(s, o).radiance, floor, [&](Vec3, Vec3 wo) { return want(wo); },
        Relative::mean);
  }
};

// A rough metal floor under a sky that brightens from a black horizon to a white zenith
// (L = w.y): the BRDF integrated against it. The cone query reads the lobe from the cascade whose
// cells are a quarter of its width (cascade::cone_cascade); the widest query, from cascade 0's
// 50-degree cells, takes light from higher in the sky than the lobe reaches.
TEST(GlossyCascades, TheGridsConeQueryFollowsAGradientSkyCloserThanItsWidestQuery) {
  struct Case {
    float roughness;
    double error, mean;  // the cone query's bounds
  };
  // Measured (2026-11-29, 48 x 36; the same against the path tracer at 512 samples): at 0.3
  // (K = 4) the cone 18.3% and 1.136 of the mean, the widest query 36.3% and 1.238; at 0.6
  // (K = 2) the cone 1.04% and 1.004, the widest 5.1% and 0.953. At 0.3 the far floor, which
  // mirrors the dark horizon, is too bright: a floor alone leaves the grid one probe layer high
  // at cascade 2, inside the floor, and the cone reads cascade 1 (docs/QUALITY.md).
  for (const Case& c : {Case{0.3f, 0.22, 0.17}, Case{0.6f, 0.02, 0.01}}) {
    const GradientFloor g(c.roughness);
    auto error = [&](SpecularQuery q) {
      RenderOptions o = method(Method::grid);
      o.grid.specular = q;
      return g.error(o);
    };
    const auto [cone, cone_mean] = error(SpecularQuery::cone);
    const auto [wide, wide_mean] = error(SpecularQuery::wide);
    EXPECT_LT(cone, c.error) << c.roughness << " " << wide;
    EXPECT_NEAR(cone_mean, 1, c.mean) << c.roughness << " " << wide_mean;
    EXPECT_LT(cone, 0.6 * wide) << c.roughness;
  }
}

// The same gradient sky through ssrc's and the surface cascades' only query, the widest: the lobe
// weighed over merged cascade 0's bins (ssrc: 16 screen directions x 8 bins of 4 sectors) and
// texel maps (surface: 8 x 8 cells), each cell at 4 x 4 points.
TEST(GlossyCascades, TheWidestQueriesOfSsrcAndSurfaceFollowAGradientSky) {
  struct Case {
    Method m;
    float roughness;
    double error, mean;
  };
  // Measured (2026-11-30, 48 x 36): ssrc 5.7% and 1.026 of the mean at 0.3, 1.7% and 1.002 at
  // 0.6; the surface cascades 15.9% and 1.102, 2.2% and 0.980 (the grid's widest query: 36.3%
  // and 5.1%, over 16 cells).
  for (const Case& c :
       {Case{Method::ssrc, 0.3f, 0.07, 0.04}, Case{Method::ssrc, 0.6f, 0.02, 0.01},
        Case{Method::surface, 0.3f, 0.19, 0.13}, Case{Method::surface, 0.6f, 0.03, 0.03}}) {
    const auto [error, mean] = GradientFloor(c.roughness).error(method(c.m));
    EXPECT_LT(error, c.error) << to_string(c.m) << " " << c.roughness;
    EXPECT_NEAR(mean, 1, c.mean) << to_string(c.m) << " " << c.roughness;
  }
}

}  // namespace
}  // namespace penumbra::spaceland
