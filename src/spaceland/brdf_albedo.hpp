// The BRDF's directional albedo split by Fresnel (the "split sum" of Karis, "Real Shading in
// Unreal Engine 4", 2013): how much of a uniform light each lobe of glTF's BRDF (brdf.hpp)
// returns towards a viewer at cos_o = mu. The cascade methods shade a glossy surface as the
// diffuse gather times the diffuse lobe's share plus a cone of radiance about the mirrored view
// times the specular lobe's, both from these tables.
//
// Schlick's F = F0 + (1 - F0) s with s = (1 - v.h)^5 is linear in F0, so
//   specular: integral of F D V cos = F0 A(mu, alpha) + B(mu, alpha), A = int (1 - s) D V cos,
//             B = int s D V cos;
//   diffuse:  integral of (1 - F) c_diff / pi cos = c_diff (1 - F0) (1 - S(mu)),
//             S = int s cos / pi (over the hemisphere, h the half vector: alpha plays no part).
#pragma once

#include "penumbra/image.hpp"

namespace penumbra::spaceland {

struct LobeAlbedo {
  Rgb specular;  // F0 A + B
  Rgb diffuse;   // c_diff (1 - F0) (1 - S); the Lambertian: its albedo
};

// Both lobes' directional albedo for the BRDF of base colour `albedo`, metallic and roughness at
// cos_o = mu (in [0, 1]). Tables of 32 x 32 (mu, roughness) computed by quadrature (below), read
// bilinearly: within 0.5% of the integrals (tests/spaceland/brdf_test.cpp).
LobeAlbedo lobe_albedo(Rgb albedo, float metallic, float roughness, float mu);
// The same for a BRDF made already (make_brdf, brdf_at: textures applied).
struct Brdf;
LobeAlbedo lobe_albedo(const Brdf& brdf, float mu);

// The share of a uniform light the BRDF reflects over all directions (its albedo averaged over
// the viewing hemisphere, weighted by the cosine): what a method that keeps one colour per
// surface (the grid's voxels, the radiance cache) reflects of a glossy surface. The Lambertian:
// its albedo.
Rgb hemispherical_albedo(const Brdf& brdf);

// The tables' values, read bilinearly at (mu, roughness): A, B and S.
struct SplitSum {
  float a = 0, b = 0, s = 0;
};
SplitSum split_sum(float mu, float roughness);

// The tables' grid: kSplitSumSide steps of mu from 0.01 to 1 and of roughness from 0 to 1. The
// values ship in brdf_albedo_table.inc, written by tools/brdf_tables.cpp from
// integrate_split_sum (2048 Sobol points an entry, a second of work a program should not pay
// at its first glossy pixel); the tests recompute them.
inline constexpr int kSplitSumSide = 32;
float split_sum_mu(int k);
float split_sum_roughness(int j);
SplitSum integrate_split_sum(float mu, float roughness);

}  // namespace penumbra::spaceland
