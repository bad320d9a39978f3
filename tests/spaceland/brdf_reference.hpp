// The glTF 2.0 metallic-roughness BRDF written from the specification (appendix B) in double
// precision, apart from src/spaceland/brdf.hpp, and quadrature over the sphere: the tests' truth
// for the BRDF and for glossy path tracing.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "penumbra/vec3.hpp"

namespace penumbra::spaceland::testing {

constexpr double kPiD = std::numbers::pi;

// The glTF 2.0 specification's appendix B, in double: f(wo, wi) for base colour `c`.
inline double reference_f(double c, double metallic, double roughness, Vec3 n, Vec3 wo, Vec3 wi) {
  const double a = roughness * roughness, a2 = a * a;
  const double nl = dot(n, wi), nv = dot(n, wo);
  if (nl <= 0 || nv <= 0) return 0;
  const Vec3 h = normalize(wo + wi);
  const double nh = dot(n, h), vh = dot(wo, h);
  const double f0 = 0.04 * (1 - metallic) + c * metallic;
  const double F = f0 + (1 - f0) * std::pow(1 - std::abs(vh), 5);
  const double D = a2 / (kPiD * std::pow(nh * nh * (a2 - 1) + 1, 2));
  const double V =
      0.5 / (nl * std::sqrt(nv * nv * (1 - a2) + a2) + nv * std::sqrt(nl * nl * (1 - a2) + a2));
  const double diffuse = (1 - F) * c * (1 - metallic) / kPiD;
  if (a2 == 0) return diffuse;  // a mirror: its specular lobe is a delta (reference_mirror)
  return diffuse + F * D * V;
}

inline Vec3 direction(double theta, double phi) {
  return {float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
          float(std::cos(theta))};
}

// The integral over the sphere of g(w), by the midpoint rule in (cos theta, phi) about `axis`
// with cos theta spaced densely near the axis (where a narrow lobe lives).
template <class G>
double sphere_integral(Vec3 axis, G&& g, int rings = 800, int sectors = 400) {
  Vec3 t, b;
  orthonormal_basis(axis, t, b);
  double sum = 0;
  for (int i = 0; i < rings; ++i) {
    // 1 - cos = 2 s^3: rings bunch near the axis; d(cos) = 6 s^2 ds.
    const double s = (i + 0.5) / rings, one_minus_cos = 2 * s * s * s;
    const double c = 1 - one_minus_cos, sn = std::sqrt(std::max(0.0, 1 - c * c));
    const double dcos = 6 * s * s / rings;
    for (int k = 0; k < sectors; ++k) {
      const double phi = 2 * kPiD * (k + 0.5) / sectors;
      const Vec3 w = normalize(axis * float(c) + t * float(sn * std::cos(phi)) +
                               b * float(sn * std::sin(phi)));
      sum += g(w) * dcos * (2 * kPiD / sectors);
    }
  }
  return sum;
}

// The integral of g(w) over the cone about `axis` whose half-angle has 1 - cos = `width`, by the
// midpoint rule in (cos theta, phi).
template <class G>
double cone_integral(Vec3 axis, double width, G&& g, int rings = 100, int sectors = 100) {
  Vec3 t, b;
  orthonormal_basis(axis, t, b);
  double sum = 0;
  for (int i = 0; i < rings; ++i) {
    const double c = 1 - width * (i + 0.5) / rings, sn = std::sqrt(std::max(0.0, 1 - c * c));
    for (int k = 0; k < sectors; ++k) {
      const double phi = 2 * kPiD * (k + 0.5) / sectors;
      const Vec3 w = normalize(axis * float(c) + t * float(sn * std::cos(phi)) +
                               b * float(sn * std::sin(phi)));
      sum += g(w);
    }
  }
  return sum * (width / rings) * (2 * kPiD / sectors);
}

// A mirror's (roughness 0) delta: Schlick's Fresnel at the viewing angle.
inline double reference_mirror(double c, double metallic, Vec3 n, Vec3 wo) {
  const double f0 = 0.04 * (1 - metallic) + c * metallic;
  return f0 + (1 - f0) * std::pow(1 - double(dot(n, wo)), 5);
}

// Directional albedo: the integral of f cos over the hemisphere about n, seen from wo (a
// mirror's delta included).
inline double reference_albedo(double c, double metallic, double roughness, Vec3 n, Vec3 wo,
                               int rings = 800, int sectors = 400) {
  const Vec3 r = normalize(n * float(2 * dot(n, wo)) - wo);
  return (roughness == 0 ? reference_mirror(c, metallic, n, wo) : 0.0) +
         sphere_integral(
             r,
             [&](Vec3 wi) {
               const double nl = dot(n, wi);
               return nl > 0 ? reference_f(c, metallic, roughness, n, wo, wi) * nl : 0.0;
             },
             rings, sectors);
}

// reference_albedo about n = +y as a function of the viewing cosine, tabulated on 97 points
// and read linearly (each a quadrature of 80,000 points).
class AlbedoTable {
 public:
  AlbedoTable(double c, double metallic, double roughness) : values_(kSteps + 1) {
    for (int k = 0; k <= kSteps; ++k) {
      const double m = std::max(1e-3, double(k) / kSteps);
      const Vec3 wo{float(std::sqrt(1 - m * m)), float(m), 0};
      values_[std::size_t(k)] = reference_albedo(c, metallic, roughness, {0, 1, 0}, wo, 400, 200);
    }
  }
  double operator()(double cos_o) const {
    const double x = std::clamp(cos_o, 0.0, 1.0) * kSteps;
    const int k = std::min(kSteps - 1, int(x));
    return values_[std::size_t(k)] +
           (x - k) * (values_[std::size_t(k) + 1] - values_[std::size_t(k)]);
  }

 private:
  static constexpr int kSteps = 96;
  std::vector<double> values_;
};

}  // namespace penumbra::spaceland::testing
