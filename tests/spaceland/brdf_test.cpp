// glTF's metallic-roughness BRDF (src/spaceland/brdf.hpp) against independent truth: the
// specification's formulas written again here in double precision, numerical integrals over the
// sphere, reciprocity, the sampler's histogram against its density, and energy (a white furnace
// never gains, and loses what single-scattering GGX is known to lose at high roughness).
#include "spaceland/brdf.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/sobol.hpp"
#include "spaceland/brdf_albedo.hpp"
#include "spaceland/brdf_reference.hpp"
#include "spaceland/cascade/cone.hpp"

namespace penumbra::spaceland {
namespace {

using namespace penumbra::spaceland::testing;

const Vec3 kN{0, 0, 1};

TEST(SpacelandBrdf, MatchesTheSpecificationsFormulasAndTheLambertianRule) {
  for (double metallic : {0.0, 0.3, 1.0})
    for (double roughness : {0.1, 0.5, 1.0}) {
      const Brdf b = make_brdf({0.7f, 0.7f, 0.7f}, float(metallic), float(roughness));
      for (double to : {0.0, 0.7, 1.4})
        for (double ti : {0.1, 0.8, 1.5})
          for (double phi : {0.0, 2.0, 3.1}) {
            const Vec3 wo = direction(to, 0), wi = direction(ti, phi);
            const double got = brdf_cos(b, kN, kN, wo, wi).g / dot(kN, wi);
            const double want = metallic == 0 && roughness == 1
                                    ? 0.7 / kPiD
                                    : reference_f(0.7, metallic, roughness, kN, wo, wi);
            EXPECT_NEAR(got / want, 1.0, 2e-4)
                << "metallic " << metallic << " roughness " << roughness << " at " << to << ", "
                << ti << ", " << phi;
          }
    }
  // metallic 0, roughness 1 is version 1's Lambertian: no Fresnel, no lobe.
  EXPECT_TRUE(make_brdf({0.5f, 0.5f, 0.5f}, 0, 1).lambertian);
  EXPECT_FALSE(make_brdf({0.5f, 0.5f, 0.5f}, 0, 0.99f).lambertian);
}

TEST(SpacelandBrdf, IsReciprocal) {
  const Brdf b = make_brdf({0.9f, 0.6f, 0.3f}, 0.4f, 0.35f);
  for (double to : {0.2, 0.9, 1.3})
    for (double ti : {0.05, 0.6, 1.45}) {
      const Vec3 wo = direction(to, 0.3), wi = direction(ti, 2.2);
      const Rgb a = brdf_cos(b, kN, kN, wo, wi) * (1 / dot(kN, wi));
      const Rgb c = brdf_cos(b, kN, kN, wi, wo) * (1 / dot(kN, wo));
      EXPECT_NEAR(a.r / c.r, 1, 1e-4);
      EXPECT_NEAR(a.b / c.b, 1, 1e-4);
    }
}

TEST(SpacelandBrdf, TheSamplersDensityIntegratesToOneOverTheSphere) {
  // The visible-normal density G1(wo) D(h) / (4 cos_o) over every reflected direction (those under
  // the surface included, which the sampler draws and the path drops), from the formula of the
  // reference, not brdf_pdf.
  for (double roughness : {0.15, 0.3, 0.6, 1.0})
    for (double theta_o : {0.0, 0.8, 1.4}) {
      const double a = roughness * roughness, a2 = a * a;
      const Vec3 wo = direction(theta_o, 0);
      const double co = dot(kN, wo);
      const double g1 = 2 * co / (co + std::sqrt(a2 + (1 - a2) * co * co));
      const Vec3 r = normalize(kN * float(2 * co) - wo);
      const double total = sphere_integral(r, [&](Vec3 wi) {
        const Vec3 hv = wo + wi;
        if (length(hv) < 1e-6f) return 0.0;
        const Vec3 h = normalize(hv);
        const double nh = dot(kN, h);
        if (nh <= 0 || dot(wo, h) <= 0) return 0.0;
        const double D = a2 / (kPiD * std::pow(nh * nh * (a2 - 1) + 1, 2));
        return g1 * D / (4 * co);
      });
      EXPECT_NEAR(total, 1.0, 3e-3) << "roughness " << roughness << " theta_o " << theta_o;
      // brdf_pdf (metal: the specular lobe alone) is that density above the surface.
      const Brdf b = make_brdf({1, 1, 1}, 1, float(roughness));
      const double above =
          sphere_integral(r, [&](Vec3 wi) { return double(brdf_pdf(b, kN, kN, wo, wi)); });
      // Rough lobes reflect much of their mass under the surface, a narrow one seen head-on
      // none.
      EXPECT_LE(above, 1.003);
      if (roughness < 0.2 && theta_o == 0) {
        EXPECT_GT(above, 0.997);
      }
    }
}

TEST(SpacelandBrdf, SamplesFallWhereTheirDensitySays) {
  // A histogram of sampled directions in bins of (cos theta, phi) against the integral of
  // brdf_pdf over each bin: glossy metal and a glossy dielectric (both lobes, one picked).
  for (const auto& [metallic, roughness] : {std::pair{1.0f, 0.3f}, std::pair{0.0f, 0.5f}}) {
    const Brdf b = make_brdf({0.8f, 0.8f, 0.8f}, metallic, roughness);
    const Vec3 wo = direction(0.9, 0);
    constexpr int kRings = 16, kSectors = 16, kSamples = 1 << 20;
    std::vector<double> counts(kRings * kSectors, 0);
    int drawn = 0;
    for (std::uint32_t i = 0; i < kSamples; ++i) {
      const auto u = sobol::sample_2d(i, 7, 0);
      const auto v = sobol::sample_2d(i, 7, 1);
      const BrdfSample s = sample_brdf(b, kN, kN, wo, v[0], u);
      if (is_black(s.weight)) continue;
      ++drawn;
      const double c = dot(kN, s.wi);
      double phi = std::atan2(double(s.wi.y), double(s.wi.x));
      if (phi < 0) phi += 2 * kPiD;
      const int ring = std::min(kRings - 1, int(c * kRings));
      const int sector = std::min(kSectors - 1, int(phi / (2 * kPiD) * kSectors));
      counts[ring * kSectors + sector] += 1;
    }
    double worst = 0, mass = 0;
    for (int ring = 0; ring < kRings; ++ring)
      for (int sector = 0; sector < kSectors; ++sector) {
        // The bin's probability: brdf_pdf integrated by a 12 x 12 midpoint rule.
        double p = 0;
        for (int a = 0; a < 12; ++a)
          for (int q = 0; q < 12; ++q) {
            const double c = (ring + (a + 0.5) / 12) / kRings;
            const double phi = 2 * kPiD * (sector + (q + 0.5) / 12) / kSectors;
            p += brdf_pdf(b, kN, kN, wo, direction(std::acos(c), phi)) * (1.0 / (kRings * 12)) *
                 (2 * kPiD / (kSectors * 12));
          }
        mass += p;
        const double got = counts[ring * kSectors + sector] / kSamples;
        if (p > 1e-3) worst = std::max(worst, std::abs(got / p - 1));
      }
    EXPECT_NEAR(double(drawn) / kSamples, mass, 5e-3) << "metallic " << metallic;
    EXPECT_LT(worst, 0.05) << "metallic " << metallic;
  }
}

double albedo_at_angle(double c, double metallic, double roughness, double theta_o) {
  return testing::reference_albedo(c, metallic, roughness, kN, direction(theta_o, 0));
}

TEST(SpacelandBrdf, SampleWeightsAverageToTheDirectionalAlbedo) {
  // The mean of f cos / pdf over the sampler's draws is the hemisphere integral of f cos.
  for (const auto& [metallic, roughness] :
       {std::pair{1.0f, 0.2f}, std::pair{1.0f, 0.6f}, std::pair{0.0f, 0.4f}, std::pair{0.5f, 1.0f}})
    for (double theta_o : {0.3, 1.2}) {
      const Brdf b = make_brdf({0.8f, 0.8f, 0.8f}, metallic, roughness);
      const Vec3 wo = direction(theta_o, 0);
      constexpr int kSamples = 1 << 16;
      double sum = 0;
      for (std::uint32_t i = 0; i < kSamples; ++i) {
        const BrdfSample s =
            sample_brdf(b, kN, kN, wo, sobol::sample_2d(i, 3, 1)[0], sobol::sample_2d(i, 3, 0));
        sum += s.weight.g;
      }
      const double want = albedo_at_angle(0.8, metallic, roughness, theta_o);
      EXPECT_NEAR(sum / kSamples / want, 1.0, 0.01)
          << "metallic " << metallic << " roughness " << roughness << " theta_o " << theta_o;
    }
}

TEST(SpacelandBrdf, AWhiteFurnaceNeverGainsAndLosesWhatSingleScatteringLoses) {
  // A white metal (F = 1): the directional albedo is the microfacet masking's alone, at most 1,
  // close to 1 when smooth, and well below it at roughness 1, where single scattering drops the
  // light that bounces between microfacets (Kulla and Conty 2017). There D = 1 / pi and the
  // height-correlated V = 1 / (2 (cos_i + cos_o)), so the albedo at cos_o = m is the integral
  // of c / (c + m) over c in [0, 1]: 1 - m ln(1 + 1 / m), 1 - ln 2 head-on.
  double smooth_worst = 1, rough_normal = 0;
  for (double roughness : {0.1, 0.3, 0.6, 1.0})
    for (double theta_o : {0.0, 0.5, 1.0, 1.4}) {
      const double e = albedo_at_angle(1, 1, roughness, theta_o);
      EXPECT_LE(e, 1.0 + 2e-3) << roughness << " " << theta_o;
      if (roughness == 0.1) smooth_worst = std::min(smooth_worst, e);
      if (roughness == 1.0) {
        const double m = std::cos(theta_o);
        EXPECT_NEAR(e, 1 - m * std::log(1 + 1 / m), 2e-3) << theta_o;
        if (theta_o == 0.0) rough_normal = e;
      }
      // The sampler's weights agree (they are f cos / pdf, with F = 1: G2 / G1 <= 1).
      const Brdf b = make_brdf({1, 1, 1}, 1, float(roughness));
      const Vec3 wo = direction(theta_o, 0);
      double sum = 0;
      for (std::uint32_t i = 0; i < 4096; ++i) {
        const BrdfSample s = sample_brdf(b, kN, kN, wo, 0, sobol::sample_2d(i, 5, 0));
        EXPECT_LE(s.weight.g, 1.0f + 1e-5f);
        sum += s.weight.g;
      }
      EXPECT_NEAR(sum / 4096 / e, 1.0, 0.01) << roughness << " " << theta_o;
    }
  EXPECT_GT(smooth_worst, 0.97);
  EXPECT_NEAR(rough_normal, 1 - std::log(2.0), 2e-3);
}

TEST(SpacelandBrdf, TheSplitSumTablesGiveEachLobesDirectionalAlbedo) {
  // Off the tables' grid: the two lobes' albedos add up to the hemisphere integral of f cos.
  double worst = 0;
  for (double metallic : {0.0, 0.4, 1.0})
    for (double roughness : {0.05, 0.23, 0.5, 0.77, 0.97})
      for (double theta_o : {0.1, 0.7, 1.2, 1.45}) {
        const LobeAlbedo l = lobe_albedo({0.8f, 0.8f, 0.8f}, float(metallic), float(roughness),
                                         float(std::cos(theta_o)));
        const double want = albedo_at_angle(0.8, metallic, roughness, theta_o);
        const double got = l.specular.g + l.diffuse.g;
        worst = std::max(worst, std::abs(got / want - 1));
        EXPECT_NEAR(got / want, 1, 0.005)
            << "metallic " << metallic << " roughness " << roughness << " theta " << theta_o;
      }
  EXPECT_LT(worst, 0.005);
  // Closed forms: a mirror's F is Schlick's at the viewing angle (A = 1 - s, B = s); a white
  // rough metal's albedo is 1 - m ln(1 + 1/m); the Lambertian is its albedo alone.
  for (double m : {0.2, 0.6, 0.95}) {
    const SplitSum mirror = split_sum(float(m), 0);
    EXPECT_NEAR(mirror.b, std::pow(1 - m, 5), 2e-3) << m;
    EXPECT_NEAR(mirror.a + mirror.b, 1, 2e-3) << m;
    const SplitSum rough = split_sum(float(m), 1);
    EXPECT_NEAR(rough.a + rough.b, 1 - m * std::log(1 + 1 / m), 3e-3) << m;
  }
  const LobeAlbedo lambert = lobe_albedo({0.3f, 0.5f, 0.7f}, 0, 1, 0.5f);
  EXPECT_EQ(lambert.diffuse.b, 0.7f);
  EXPECT_EQ(lambert.specular.b, 0.0f);
}

TEST(SpacelandBrdf, TheShippedSplitSumTablesAreTheirQuadrature) {
  // src/spaceland/brdf_albedo_table.inc against integrate_split_sum, entry by entry (at the
  // grid's points the bilinear read is the entry); tools/brdf_tables.cpp rewrites the file.
  double worst = 0;
  for (int j = 0; j < kSplitSumSide; ++j)
    for (int k = 0; k < kSplitSumSide; ++k) {
      const float mu = split_sum_mu(k), r = split_sum_roughness(j);
      const SplitSum want = integrate_split_sum(mu, r), got = split_sum(mu, r);
      worst = std::max({worst, double(std::abs(got.a - want.a)), double(std::abs(got.b - want.b)),
                        double(std::abs(got.s - want.s))});
    }
  EXPECT_LT(worst, 1e-5) << "regenerate: build/bin/penumbra_brdf_tables > "
                            "src/spaceland/brdf_albedo_table.inc";
}

TEST(SpacelandBrdf, AMirrorReflectsExactlyWithSchlicksFresnel) {
  const Brdf b = make_brdf({0.9f, 0.5f, 0.2f}, 1, 0);
  ASSERT_TRUE(b.mirror());
  const Vec3 wo = direction(1.0, 0.4);
  const BrdfSample s = sample_brdf(b, kN, kN, wo, 0.5f, {0.3f, 0.7f});
  EXPECT_TRUE(s.delta);
  const Vec3 want = normalize(kN * float(2 * dot(kN, wo)) - wo);
  EXPECT_NEAR(dot(s.wi, want), 1.0, 1e-6);
  const double w5 = std::pow(1 - std::cos(1.0), 5);
  EXPECT_NEAR(s.weight.r, 0.9 + 0.1 * w5, 1e-5);
  EXPECT_NEAR(s.weight.b, 0.2 + 0.8 * w5, 1e-5);
  // No density: a light sample never meets the delta.
  EXPECT_EQ(brdf_cos(b, kN, kN, wo, want).r, 0.0f);
}

// A light's share of a lobe (the cone query's lights met at a point): a mirror takes all of a
// light its reflection falls in and none of one beside it; a lobe wider than a small light
// takes omega w / E, E the lobe's integral (here by quadrature); a cap over the whole hemisphere
// holds the whole lobe, whichever way it is sampled.
TEST(SpacelandBrdf, ALightsShareOfALobeIsTheLobesPartInItsCap) {
  const Vec3 n{0, 0, 1}, wo = normalize(Vec3{0.5f, 0, 1});
  const float mu = dot(n, wo);
  const Vec3 r = reflect(wo, n);
  const float small = 0.01f;  // steradians: a cap 3.2 degrees in radius
  EXPECT_NEAR(cascade::lobe_share(0, n, wo, r, small, mu), 1, 1e-6);
  const Vec3 beside = normalize(r + Vec3{0, 0.1f, 0});  // 5.7 degrees off the mirror direction
  EXPECT_NEAR(cascade::lobe_share(0, n, wo, beside, small, mu), 0, 1e-6);
  for (const float alpha : {0.3f, 1.0f}) {
    const double e = cone_integral(
        n, 1, [&](Vec3 wi) { return lobe_weight(alpha, n, wo, wi); }, 400, 400);
    for (const Vec3 towards : {r, beside, normalize(Vec3{-0.3f, 0.2f, 1})}) {
      const double want = small * lobe_weight(alpha, n, wo, towards) / e;
      EXPECT_NEAR(cascade::lobe_share(alpha, n, wo, towards, small, mu), want, 0.02 * want)
          << alpha;
    }
  }
  for (const float alpha : {0.0f, 0.05f, 0.3f, 0.7f, 1.0f})
    EXPECT_NEAR(cascade::lobe_share(alpha, n, wo, n, float(2 * kPi), mu), 1, 0.03) << alpha;
}

}  // namespace
}  // namespace penumbra::spaceland
