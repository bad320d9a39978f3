#include "spaceland/brdf_albedo.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/sobol.hpp"
#include "spaceland/brdf.hpp"
#include "spaceland/color.hpp"

namespace penumbra::spaceland {

namespace {

constexpr int kSide = kSplitSumSide;
constexpr int kSamples = 2048;   // Sobol points per entry
constexpr float kMuLow = 0.01f;  // the first mu: at 0 the lobe sees nothing

// [j * kSide + k]: roughness j, mu k.
constexpr SplitSum kTable[kSide * kSide] = {
#include "spaceland/brdf_albedo_table.inc"
};

}  // namespace

float split_sum_mu(int k) {
  return kMuLow + (1 - kMuLow) * float(k) / float(kSide - 1);
}
float split_sum_roughness(int j) {
  return float(j) / float(kSide - 1);
}

// A, B by the visible-normal sampler (weight F G2 / G1 with F split in F0), S by the cosine.
SplitSum integrate_split_sum(float mu, float roughness) {
  const float alpha = roughness * roughness;
  const Vec3 n{0, 0, 1}, t{1, 0, 0}, bt{0, 1, 0};
  const Vec3 wo{std::sqrt(std::max(0.0f, 1 - mu * mu)), 0, mu};
  double a = 0, b = 0, s = 0;
  for (std::uint32_t i = 0; i < kSamples; ++i) {
    const std::array<float, 2> u = sobol::sample_2d(i, 0x5eed, 0);
    const Vec3 h = sample_visible_normal(alpha, n, t, bt, wo, u);
    const Vec3 wi = reflect(wo, h);
    const float ci = wi.z;
    if (ci > 0) {
      const float g2_over_g1 = 4 * mu * ci * brdf_detail::smith_v(std::max(alpha, 1e-7f), mu, ci) /
                               brdf_detail::smith_g1(std::max(alpha, 1e-7f), mu);
      const float c = std::clamp(1 - dot(wo, h), 0.0f, 1.0f);
      const float sh = c * c * c * c * c;
      a += (1 - sh) * g2_over_g1;
      b += sh * g2_over_g1;
    }
    // The diffuse lobe's (1 - F) under a cosine-distributed light.
    const Vec3 l = cosine_direction(n, sobol::sample_2d(i, 0x5eed, 1));
    const Vec3 hv = wo + l;
    const float hl = length(hv);
    if (hl > 0) {
      const float c = std::clamp(1 - dot(wo, hv / hl), 0.0f, 1.0f);
      s += c * c * c * c * c;
    }
  }
  return {float(a / kSamples), float(b / kSamples), float(s / kSamples)};
}

SplitSum split_sum(float mu, float roughness) {
  const float x = std::clamp((mu - kMuLow) / (1 - kMuLow), 0.0f, 1.0f) * float(kSide - 1);
  const float y = std::clamp(roughness, 0.0f, 1.0f) * float(kSide - 1);
  const int k0 = std::min(int(x), kSide - 2), j0 = std::min(int(y), kSide - 2);
  const float fx = x - float(k0), fy = y - float(j0);
  auto get = [&](int j, int k) { return kTable[std::size_t(j * kSide + k)]; };
  auto mix = [&](float v00, float v10, float v01, float v11) {
    return (v00 * (1 - fx) + v10 * fx) * (1 - fy) + (v01 * (1 - fx) + v11 * fx) * fy;
  };
  const SplitSum p = get(j0, k0), q = get(j0, k0 + 1), r = get(j0 + 1, k0), w = get(j0 + 1, k0 + 1);
  return {mix(p.a, q.a, r.a, w.a), mix(p.b, q.b, r.b, w.b), mix(p.s, q.s, r.s, w.s)};
}

LobeAlbedo lobe_albedo(const Brdf& b, float mu) {
  if (b.lambertian) return {Rgb{}, b.diffuse};
  const SplitSum t = split_sum(mu, std::sqrt(b.alpha));
  const Rgb one{1, 1, 1};
  return {b.f0 * t.a + one * t.b, b.diffuse * (one - b.f0) * (1 - t.s)};
}

Rgb hemispherical_albedo(const Brdf& b) {
  if (b.lambertian) return b.diffuse;
  // 2 mu dmu by the midpoint rule on 16 steps.
  Rgb sum{};
  constexpr int kSteps = 16;
  for (int k = 0; k < kSteps; ++k) {
    const float mu = (float(k) + 0.5f) / float(kSteps);
    const LobeAlbedo l = lobe_albedo(b, mu);
    sum += (l.specular + l.diffuse) * (2 * mu / float(kSteps));
  }
  return sum;
}

LobeAlbedo lobe_albedo(Rgb albedo, float metallic, float roughness, float mu) {
  return lobe_albedo(make_brdf(albedo, metallic, roughness), mu);
}

}  // namespace penumbra::spaceland
