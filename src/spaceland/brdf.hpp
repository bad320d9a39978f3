// glTF 2.0's metallic-roughness BRDF (docs/scene-format.md, "Glossy materials"; the glTF
// specification, appendix B): a GGX (Trowbridge-Reitz) specular lobe with Smith height-correlated
// masking and Schlick's Fresnel, over a Lambertian lobe weighted by 1 - F. Version 1's Lambertian
// (metallic 0, roughness 1) stays albedo / pi exactly, so that its images do not change.
//
// Every function works in world space about the shading normal `n`, turned to the side the light
// leaves towards (`wo`, unit, dot(n, wo) >= 0). Values are the BRDF times the cosine of the
// arriving direction `wi`, the quantity a path's throughput takes.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "core/math.hpp"
#include "penumbra/vec3.hpp"
#include "spaceland/color.hpp"
#include "spaceland/sampling.hpp"

namespace penumbra::spaceland {

// Below this alpha (roughness about 0.03) the specular lobe is a perfect mirror, a direction
// rather than a density: GGX evaluated there overflows a float long before it sharpens
// visibly (pbrt-v4 takes the same bound).
inline constexpr float kMirrorAlpha = 1e-3f;

// The BRDF at one surface point.
struct Brdf {
  Rgb diffuse{};           // Lambertian colour: albedo (1 - metallic); albedo where lambertian
  Rgb f0{};                // Fresnel reflectance at normal incidence: mix(0.04, albedo, metallic)
  float alpha = 1;         // GGX width, roughness^2
  bool lambertian = true;  // version 1's Lambertian: albedo / pi, no specular lobe

  // The specular lobe is a perfect mirror: a delta that no light sample can meet.
  bool mirror() const { return !lambertian && alpha < kMirrorAlpha; }
};

// The BRDF of base colour `albedo` with `metallic` and `roughness` (both in [0, 1]).
inline Brdf make_brdf(Rgb albedo, float metallic, float roughness) {
  Brdf b;
  b.lambertian = metallic == 0 && roughness == 1;
  if (b.lambertian) {
    b.diffuse = albedo;
    return b;
  }
  const float m = std::clamp(metallic, 0.0f, 1.0f);
  b.diffuse = albedo * (1 - m);
  b.f0 = Rgb{0.04f, 0.04f, 0.04f} * (1 - m) + albedo * m;
  const float r = std::clamp(roughness, 0.0f, 1.0f);
  b.alpha = r * r;
  return b;
}

namespace brdf_detail {

inline Rgb schlick(Rgb f0, float cos_theta) {
  const float c = std::clamp(1 - cos_theta, 0.0f, 1.0f);
  const float c2 = c * c, w = c2 * c2 * c;
  return f0 + (Rgb{1, 1, 1} - f0) * w;
}

// GGX normal distribution at cos(n, h) = nh.
inline float ggx_d(float alpha, float nh) {
  const float a2 = alpha * alpha;
  const float t = nh * nh * (a2 - 1) + 1;
  return a2 / (float(kPi) * t * t);
}

// Smith's masking of one direction at cos(n, w) = c (the uncorrelated G1 the visible-normal
// sampler's density carries).
inline float smith_g1(float alpha, float c) {
  const float a2 = alpha * alpha;
  return 2 * c / (c + std::sqrt(a2 + (1 - a2) * c * c));
}

// Height-correlated Smith visibility G2 / (4 cos_o cos_i), as glTF writes it.
inline float smith_v(float alpha, float co, float ci) {
  const float a2 = alpha * alpha;
  const float go = ci * std::sqrt(co * co * (1 - a2) + a2);
  const float gi = co * std::sqrt(ci * ci * (1 - a2) + a2);
  const float s = go + gi;
  return s > 0 ? 0.5f / s : 0;
}

// Mean of the three channels, the weight a lobe gets when one is picked.
inline float weight(Rgb c) {
  return average(c);
}

}  // namespace brdf_detail

// The probability of sampling the specular lobe at this outgoing direction: its Fresnel
// reflectance against the diffuse lobe's, so that a dark metal or a white plaster each get the
// samples they need. 0 for the Lambertian, 1 where the diffuse colour is black.
inline float specular_probability(const Brdf& b, float cos_o) {
  if (b.lambertian) return 0;
  const Rgb f = brdf_detail::schlick(b.f0, cos_o);
  const float s = brdf_detail::weight(f);
  const float d = brdf_detail::weight(b.diffuse) * (1 - s);
  if (!(d > 0)) return 1;
  return std::clamp(s / (s + d), 0.05f, 0.95f);
}

// f(wo, wi) cos(n, wi) of the lobes that have a density (the mirror's delta excluded). `ng`, the
// geometric normal on wo's side, stops light from under the surface.
inline Rgb brdf_cos(const Brdf& b, Vec3 n, Vec3 ng, Vec3 wo, Vec3 wi) {
  if (dot(ng, wi) <= 0) return {};
  const float ci = dot(n, wi);
  if (ci <= 0) return {};
  if (b.lambertian) return b.diffuse * (ci * float(1 / kPi));
  const float co = std::max(dot(n, wo), 0.0f);
  const Vec3 hv = wo + wi;
  const float hl = length(hv);
  if (!(hl > 0)) return {};
  const Vec3 h = hv / hl;
  const Rgb f = brdf_detail::schlick(b.f0, std::max(dot(wo, h), 0.0f));
  Rgb out = (Rgb{1, 1, 1} - f) * b.diffuse * (ci * float(1 / kPi));
  if (!b.mirror() && co > 0) {
    const float spec = brdf_detail::ggx_d(b.alpha, std::max(dot(n, h), 0.0f)) *
                       brdf_detail::smith_v(b.alpha, co, ci) * ci;
    out += f * spec;
  }
  return out;
}

// The density (per solid angle) with which sample_brdf draws wi, its delta excluded.
inline float brdf_pdf(const Brdf& b, Vec3 n, Vec3 ng, Vec3 wo, Vec3 wi) {
  if (dot(ng, wi) <= 0) return 0;
  const float ci = dot(n, wi);
  if (ci <= 0) return 0;
  const float diffuse_pdf = ci * float(1 / kPi);
  if (b.lambertian) return diffuse_pdf;
  const float co = std::max(dot(n, wo), 0.0f);
  const float ps = specular_probability(b, co);
  float pdf = (1 - ps) * diffuse_pdf;
  if (!b.mirror() && co > 0) {
    const Vec3 hv = wo + wi;
    const float hl = length(hv);
    if (hl > 0) {
      const Vec3 h = hv / hl;
      // Visible normals: D_wo(h) = G1(wo) max(0, wo.h) D(h) / cos_o, then the reflection's
      // Jacobian 1 / (4 wo.h).
      const float nh = std::max(dot(n, h), 0.0f);
      pdf += ps * brdf_detail::smith_g1(b.alpha, co) * brdf_detail::ggx_d(b.alpha, nh) / (4 * co);
    }
  }
  return pdf;
}

struct BrdfSample {
  Vec3 wi;
  Rgb weight{};        // f cos / pdf (the mirror: F / its probability)
  float pdf = 0;       // density of wi; 0 with `delta`
  bool delta = false;  // the mirror's reflection: no light sample could have drawn it
};

// Heitz, "Sampling the GGX Distribution of Visible Normals" (JCGT 2018): a microfacet normal
// seen from wo, in the frame (t, b, n).
inline Vec3 sample_visible_normal(float alpha, Vec3 n, Vec3 t, Vec3 bt, Vec3 wo,
                                  std::array<float, 2> u) {
  const Vec3 lo{dot(wo, t), dot(wo, bt), dot(wo, n)};
  const Vec3 vh = normalize(Vec3{alpha * lo.x, alpha * lo.y, lo.z});
  const float lensq = vh.x * vh.x + vh.y * vh.y;
  const Vec3 t1 = lensq > 0 ? Vec3{-vh.y, vh.x, 0} / std::sqrt(lensq) : Vec3{1, 0, 0};
  const Vec3 t2 = cross(vh, t1);
  const float r = std::sqrt(u[0]), phi = float(kTwoPi) * u[1];
  const float p1 = r * std::cos(phi);
  float p2 = r * std::sin(phi);
  const float s = 0.5f * (1 + vh.z);
  p2 = (1 - s) * std::sqrt(std::max(0.0f, 1 - p1 * p1)) + s * p2;
  const Vec3 nh = t1 * p1 + t2 * p2 + vh * std::sqrt(std::max(0.0f, 1 - p1 * p1 - p2 * p2));
  const Vec3 ne = normalize(Vec3{alpha * nh.x, alpha * nh.y, std::max(1e-6f, nh.z)});
  return t * ne.x + bt * ne.y + n * ne.z;
}

inline Vec3 reflect(Vec3 wo, Vec3 h) {
  return h * (2 * dot(wo, h)) - wo;
}

// Draws an arriving direction: the specular lobe with specular_probability (by `pick`), else
// the cosine-weighted diffuse lobe; `u` places it. A failed draw (under the surface) has a
// black weight.
inline BrdfSample sample_brdf(const Brdf& b, Vec3 n, Vec3 ng, Vec3 wo, float pick,
                              std::array<float, 2> u) {
  BrdfSample s;
  if (b.lambertian) {
    s.wi = cosine_direction(n, u);
    if (dot(s.wi, ng) <= 0) return s;
    s.pdf = std::max(dot(n, s.wi), 0.0f) * float(1 / kPi);
    if (s.pdf > 0) s.weight = b.diffuse;
    return s;
  }
  const float co = std::max(dot(n, wo), 0.0f);
  const float ps = specular_probability(b, co);
  const bool specular = pick < ps;
  if (specular && b.mirror()) {
    s.wi = reflect(wo, n);
    s.delta = true;
    if (dot(s.wi, ng) <= 0 || dot(s.wi, n) <= 0) return s;
    s.weight = brdf_detail::schlick(b.f0, co) * (1 / ps);
    return s;
  }
  if (specular) {
    if (!(co > 0)) return s;
    Vec3 t, bt;
    orthonormal_basis(n, t, bt);
    const Vec3 h = sample_visible_normal(b.alpha, n, t, bt, wo, u);
    s.wi = reflect(wo, h);
  } else {
    s.wi = cosine_direction(n, u);
  }
  s.pdf = brdf_pdf(b, n, ng, wo, s.wi);
  if (!(s.pdf > 0)) return s;
  s.weight = brdf_cos(b, n, ng, wo, s.wi) * (1 / s.pdf);
  return s;
}

// The GGX width whose lobe's median cone (half-angle 2 atan(alpha): the half vector lies within
// atan(alpha) of the normal half the time) has the given solid angle (cap_alpha), or that of one
// cell of an equal-area direction map of side `side`, 4 pi / side^2: the narrowest lobe such a
// map resolves (cell_alpha).
inline float cap_alpha(double solid_angle) {
  const double half_angle = std::acos(std::clamp(1 - solid_angle / (2 * kPi), -1.0, 1.0));
  return float(std::tan(half_angle / 2));
}
inline float cell_alpha(int side) {
  return cap_alpha(4 * kPi / (double(side) * side));
}

// The specular lobe's shape for averaging radiance over it (a cone query): D V cos at wi with
// Fresnel left out (the split sum carries it), GGX of width alpha. Zero under the surface.
inline float lobe_weight(float alpha, Vec3 n, Vec3 wo, Vec3 wi) {
  const float ci = dot(n, wi), co = std::max(dot(n, wo), 1e-4f);
  if (ci <= 0) return 0;
  const Vec3 hv = wo + wi;
  const float hl = length(hv);
  if (!(hl > 0)) return 0;
  return brdf_detail::ggx_d(alpha, std::max(dot(n, hv / hl), 0.0f)) *
         brdf_detail::smith_v(alpha, co, ci) * ci;
}

}  // namespace penumbra::spaceland
