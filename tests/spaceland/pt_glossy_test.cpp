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

// A floor (a disk 1000 across at y = 0) of base colour `c`, metallic and roughness, seen from
// above at a slant; returns its object.
int add_glossy_floor(Scene& s, Rgb c, float metallic, float roughness) {
  const int object = add_floor(s, 1000, c);
  Material& m = s.materials[s.disks.back().material];
  m.metallic = metallic;
  m.roughness = roughness;
  return object;
}

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

// Relative RMS error and mean ratio of the floor's pixels against want(p, wo).
template <class Want>
std::pair<double, double> glossy_floor_error(const Scene& s, const ImageRgb& img, int floor,
                                             Want&& want) {
  const FirstHits hits = first_hits(s);
  double sum = 0, got_sum = 0, want_sum = 0;
  int n = 0;
  for (int j = 0; j < img.height(); ++j)
    for (int i = 0; i < img.width(); ++i) {
      if (int(hits.object.at(i, j).r) != floor) continue;
      const Rgb q = hits.position.at(i, j);
      const Vec3 p{q.r, q.g, q.b};
      const double w = want(p, normalize(s.camera.position - p));
      const double got = img.at(i, j).g;
      sum += (got / w - 1) * (got / w - 1);
      got_sum += got;
      want_sum += w;
      ++n;
    }
  EXPECT_GT(n, 300);
  return {std::sqrt(sum / std::max(n, 1)), got_sum / want_sum};
}

TEST(SpacelandPtGlossy, AGlossyFloorUnderAUniformSkyShowsItsDirectionalAlbedo) {
  const Vec3 n{0, 1, 0};
  for (const auto& [metallic, roughness] :
       {std::pair{0.0f, 0.3f}, std::pair{1.0f, 0.5f}, std::pair{0.5f, 0.8f}}) {
    Scene s = floor_scene({1, 1, 1});
    const int floor = add_glossy_floor(s, {0.7f, 0.7f, 0.7f}, metallic, roughness);
    // The albedo depends on the angle alone: tabulated over cos_o, interpolated linearly.
    constexpr int kSteps = 128;
    std::vector<double> table(kSteps + 1);
    for (int k = 0; k <= kSteps; ++k) {
      const double c = std::max(1e-3, double(k) / kSteps);
      const Vec3 wo{float(std::sqrt(1 - c * c)), float(c), 0};
      table[std::size_t(k)] = reference_albedo(0.7, metallic, roughness, n, wo);
    }
    auto want = [&](Vec3, Vec3 wo) {
      const double x = std::clamp(double(wo.y), 0.0, 1.0) * kSteps;
      const int k = std::min(kSteps - 1, int(x));
      return table[std::size_t(k)] + (x - k) * (table[std::size_t(k) + 1] - table[std::size_t(k)]);
    };
    const auto [e64, mean64] = glossy_floor_error(s, render_ok(s, pt(64)).radiance, floor, want);
    const auto [e256, mean256] = glossy_floor_error(s, render_ok(s, pt(256)).radiance, floor, want);
    EXPECT_NEAR(mean256, 1.0, 0.003) << metallic << " " << roughness;
    EXPECT_LT(e256, 0.02) << metallic << " " << roughness;
    EXPECT_LT(e256, 0.6 * e64) << metallic << " " << roughness;
    (void)mean64;
  }
}

TEST(SpacelandPtGlossy, ARoughMetalFloorUnderASphereLightIntegratesTheBrdfOverTheLight) {
  const Vec3 n{0, 1, 0};
  for (float roughness : {0.15f, 0.3f, 0.6f}) {
    Scene s = floor_scene({0, 0, 0});
    const int floor = add_glossy_floor(s, {0.9f, 0.9f, 0.9f}, 1, roughness);
    const float le = 5;
    const Sphere light =
        add_sphere(s, {0, 1.0f, -1.5f}, 0.3f, add_material(s, {0, 0, 0}, {le, le, le}));
    auto want = [&](Vec3 p, Vec3 wo) {
      const Vec3 to = light.center - p;
      const double d = length(to), sin_max = light.radius / d;
      const double width = 1 - std::sqrt(1 - sin_max * sin_max);
      return le * cone_integral(to / float(d), width, [&](Vec3 wi) {
               const double nl = dot(n, wi);
               return nl > 0 ? reference_f(0.9, 1, roughness, n, wo, wi) * nl : 0.0;
             });
    };
    const auto [e64, mean64] = glossy_floor_error(s, render_ok(s, pt(64)).radiance, floor, want);
    const auto [e256, mean256] = glossy_floor_error(s, render_ok(s, pt(256)).radiance, floor, want);
    EXPECT_NEAR(mean256, 1.0, 0.003) << roughness;
    EXPECT_LT(e256, 0.01) << roughness;
    EXPECT_LT(e256, 0.6 * e64) << roughness;
    (void)mean64;
  }
}

}  // namespace
}  // namespace penumbra::spaceland
