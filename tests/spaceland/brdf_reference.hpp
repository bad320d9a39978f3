// The glTF 2.0 metallic-roughness BRDF written from the specification (appendix B) in double
// precision, apart from src/spaceland/brdf.hpp, and quadrature over the sphere: the tests' truth
// for the BRDF and for glossy path tracing.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>

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

// Directional albedo: the integral of f cos over the hemisphere about n, seen from wo.
inline double reference_albedo(double c, double metallic, double roughness, Vec3 n, Vec3 wo) {
  const Vec3 r = normalize(n * float(2 * dot(n, wo)) - wo);
  return sphere_integral(r, [&](Vec3 wi) {
    const double nl = dot(n, wi);
    return nl > 0 ? reference_f(c, metallic, roughness, n, wo, wi) * nl : 0.0;
  });
}

}  // namespace penumbra::spaceland::testing
