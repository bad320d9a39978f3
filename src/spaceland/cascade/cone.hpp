// Seed 001 section 2.6's cone query, shared by the 3D methods that keep their cascades for it
// (SPWI, the grid): which cascade K a lobe reads merged, which cells of a direction map a lobe
// covers, a probe's mean over them, and the part of a lobe a light met at the point fills. (The
// surface cascades' widest query weighs their texels' maps with lobe_cells too.)
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <utility>
#include <vector>

#include "core/octahedral.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/brdf.hpp"
#include "spaceland/brdf_albedo.hpp"
#include "spaceland/cascade/levels.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland::cascade {

// The cone query's top cascade K for a lobe of GGX width alpha: the first whose cells are at
// most a kLobeCells-th of the lobe's width (cell_alpha: a cell's solid angle matched to the
// lobe's median cone), at most `top`. Cascades 0..K-1 are read unmerged, K merged. A lobe read
// over fewer cells is blurred by them, over more it reads coarser probes: measured with SPWI
// (2026-11-29, 160 x 120, against the path tracer; cells at most 1, 1/2, 1/4, 1/8 of the lobe) a
// metal floor under a gradient sky, roughness 0.3: 12.2%, 5.1%, 3.1%, 7.7%; 0.6: 4.6%, 4.6%,
// 1.5%, 0.2%; under a sphere light, roughness 0.6: 32%, 32%, 16.8%, 16.8%; 1: 5.3%, 5.3%, 5.3%,
// 5.7%.
inline constexpr float kLobeCells = 4;
inline int cone_cascade(const Levels& l, float alpha, int top) {
  int k = 0;
  while (k < top && cell_alpha(l.side(k)) > alpha / kLobeCells) ++k;
  return k;
}

// The narrowest specular lobe of the materials the scene's surfaces use (GGX alpha; a roughness
// texture may make any part of a surface a mirror: 0); infinity where none is glossy.
inline float narrowest_lobe(const Scene& scene) {
  float narrowest = std::numeric_limits<float>::infinity();
  const std::vector<char> used = materials_in_use(scene);
  for (std::size_t k = 0; k < scene.materials.size(); ++k) {
    const Material& m = scene.materials[k];
    if (!used[k] || m.lambertian()) continue;
    narrowest = std::min(narrowest, m.metallic_roughness_texture.index >= 0
                                        ? 0.0f
                                        : make_brdf(m.albedo, m.metallic, m.roughness).alpha);
  }
  return narrowest;
}

// Whether a surface of the scene is glossy (narrowest_lobe finite): what keeps or reads the
// specular lobe's data.
inline bool any_glossy(const Scene& scene) {
  return narrowest_lobe(scene) < std::numeric_limits<float>::infinity();
}

// The points a cell wider than a quarter of the lobe (kLobeCells) is weighed at along each side,
// in every method's lobe (lobe_cells' `sub`, ssrc's bins): at the cells' centres alone the lobe
// jumps from cell to cell as the mirror direction moves (the grid's metal floor at roughness 0.3
// under a sky from a black horizon to a white zenith, 96 x 72, against the path tracer: 28% with
// stripes; 2 points: 16.1%, 4: 12.1%, 8: 11.6%).
inline constexpr int kCellPoints = 4;

// The highest K a lobe of width `narrowest` or wider reaches on these levels (0: none glossy).
inline int cone_top(const Levels& l, float narrowest) {
  return narrowest < std::numeric_limits<float>::infinity()
             ? cone_cascade(l, narrowest, l.count - 1)
             : 0;
}

// A lobe's cells on a side x side map: each cell's index and weight.
using LobeCells = std::vector<std::pair<std::uint32_t, float>>;

// The lobe of width alpha about the mirror direction r, weighted (lobe_weight) over a window of
// (2 radius + 1)^2 cells about r's cell, folded across the map's edges as the octahedron folds (a
// cell past an edge is the one mirrored along it), each cell once; the whole map where the window
// would cover it.
// With `sub` > 1 each cell's weight is the mean over sub x sub points spread evenly over it
// (sub_directions): a lobe about as wide as a cell, weighed at its centre alone, jumps from cell
// to cell as the mirror direction moves (the grid's 16 cells under a gradient sky showed
// stripes across a rough floor). Maps of up to kSubSides a side only (a map's points are kept
// per thread: 196 KB at 32, 50 MB at 512); finer maps' cells are under 3.5 degrees wide.
inline constexpr int kSubSides = 32;
inline const std::vector<Vec3>& sub_directions(int side, int sub);
inline void lobe_cells(const std::vector<Vec3>& dirs, int side, float alpha, Vec3 n, Vec3 wo,
                       Vec3 r, int radius, LobeCells& out, int sub = 1) {
  out.clear();
  const std::vector<Vec3>* subs =
      sub > 1 && side <= kSubSides ? &sub_directions(side, sub) : nullptr;
  const std::size_t per_cell = std::size_t(sub) * std::size_t(sub);
  // A fold may reach a cell the window holds already: each is marked with this call's number.
  thread_local std::vector<std::uint32_t> seen;
  thread_local std::uint32_t mark = 0;
  if (seen.size() < dirs.size() || ++mark == 0) {
    seen.assign(std::max(seen.size(), dirs.size()), 0);
    mark = 1;
  }
  auto add = [&](std::size_t cell) {
    if (seen[cell] == mark) return;
    seen[cell] = mark;
    float w = 0;
    if (subs) {
      const Vec3* d = subs->data() + cell * per_cell;
      for (std::size_t k = 0; k < per_cell; ++k) w += lobe_weight(alpha, n, wo, d[k]);
    } else {
      w = lobe_weight(alpha, n, wo, dirs[cell]);
    }
    if (w > 0) out.push_back({std::uint32_t(cell), w});
  };
  if (2 * radius + 1 >= side) {
    for (std::size_t cell = 0; cell < dirs.size(); ++cell) add(cell);
    return;
  }
  const std::array<int, 2> c = octahedral::cell_of(r, side);
  for (int dv = -radius; dv <= radius; ++dv)
    for (int du = -radius; du <= radius; ++du) {
      int u = c[0] + du, v = c[1] + dv;
      if (u < 0 || u >= side) {
        u = u < 0 ? -u - 1 : 2 * side - 1 - u;
        v = side - 1 - v;
      }
      if (v < 0 || v >= side) {
        v = v < 0 ? -v - 1 : 2 * side - 1 - v;
        u = side - 1 - u;
      }
      add(std::size_t(v) * side + std::size_t(u));
    }
}

// The sub x sub points of each cell of a side x side map (cell-major: cell j side + i holds
// points sub^2 (j side + i) onwards), made once per map and thread.
inline const std::vector<Vec3>& sub_directions(int side, int sub) {
  // A deque: a map made later leaves the ones handed out where they are.
  thread_local std::deque<std::pair<std::array<int, 2>, std::vector<Vec3>>> made;
  for (const auto& [key, d] : made)
    if (key[0] == side && key[1] == sub) return d;
  std::vector<Vec3> d;
  d.reserve(std::size_t(side) * std::size_t(side) * std::size_t(sub) * std::size_t(sub));
  const double step = 2.0 / (double(side) * sub);
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i)
      for (int b = 0; b < sub; ++b)
        for (int a = 0; a < sub; ++a)
          d.push_back(
              octahedral::decode(-1 + (i * sub + a + 0.5) * step, -1 + (j * sub + b + 0.5) * step));
  made.push_back({{side, sub}, std::move(d)});
  return made.back().second;
}

// The window lobe_cells reads on cascade i's map (cells of width `cell`, cell_alpha): 3 lobe
// widths about its centre (the median cone's tan^2 law leaves 4% of the lobe outside), at most
// 33 x 33 cells (K's lobe is 4-8 cells wide); cascade 0's few cells whole.
inline int lobe_radius(int i, int side, float alpha, float cell) {
  return i == 0 ? side : std::clamp(int(std::ceil(3 * alpha / cell)), 3, 16);
}

// The part of a lobe of width alpha (about shading normal n, viewer wo, cos_o = mu) that a light
// of solid angle omega centred on direction `axis` fills, the lobe's weight over the light's cap
// over its integral (at most 1): a light of radiance L adds L times it to the lobe's mean. One
// of the two is sampled, at kCapDirections fixed points:
// - a lobe more than a quarter of the light's width (cap_alpha): the cap, at directions of
//   equal solid angle (a Fibonacci spiral), omega times their mean weight over E = A + B
//   (split_sum), the lobe taken no narrower than a point's share of the cap;
// - a lobe under a quarter of it: the lobe, by its visible normals (Heitz 2018), the part of
//   the reflected directions' weights G2 / G1 that fall in the cap (a mirror: 1 or 0).
// (Sampling the lobe from a lobe as wide as the light, 16 points, put steps across the
// highlight: a rough floor under a light of radius 0.3 at roughness 0.3, 76% against 34%.)
// Taken at the light's centre alone, omega w / E made a small light's highlight a spike (a metal
// sphere among lights of radius 0.12, roughness 0.3: 49.1% from the path tracer against 11.5%).
inline constexpr int kCapDirections = 64;
inline float lobe_share(float alpha, Vec3 n, Vec3 wo, Vec3 axis, float omega, float mu) {
  if (!(omega > 0)) return 0;
  constexpr float kGolden = 0.618034f;  // (sqrt 5 - 1) / 2
  const float one_minus_cos = std::min(2.0f, omega / float(2 * kPi));
  if (alpha < cap_alpha(omega) / kLobeCells) {
    Vec3 t, b;
    orthonormal_basis(n, t, b);
    const float co = std::max(mu, 1e-4f), g1 = brdf_detail::smith_g1(alpha, co);
    float in = 0, all = 0;
    for (int k = 0; k < kCapDirections; ++k) {
      const float u1 = float(k) * kGolden;
      const Vec3 h = sample_visible_normal(
          alpha, n, t, b, wo, {(float(k) + 0.5f) / kCapDirections, u1 - std::floor(u1)});
      const Vec3 wi = reflect(wo, h);
      const float ci = dot(n, wi);
      if (!(ci > 0)) continue;
      const float g = 4 * co * ci * brdf_detail::smith_v(alpha, co, ci) / g1;
      all += g;
      if (1 - dot(wi, axis) <= one_minus_cos) in += g;
    }
    return all > 0 ? in / all : 0;
  }
  const float width = std::min(1.0f, std::max(alpha, cap_alpha(omega / kCapDirections)));
  const SplitSum e = split_sum(mu, std::sqrt(width));
  if (!(width > 0) || !(e.a + e.b > 0)) return 0;
  Vec3 t, b;
  orthonormal_basis(axis, t, b);
  float sum = 0;
  for (int k = 0; k < kCapDirections; ++k) {
    const float c = 1 - (float(k) + 0.5f) / kCapDirections * one_minus_cos;
    const float s = std::sqrt(std::max(0.0f, 1 - c * c)), phi = float(2 * kPi) * kGolden * float(k);
    sum += lobe_weight(width, n, wo, axis * c + (t * std::cos(phi) + b * std::sin(phi)) * s);
  }
  return std::min(1.0f, omega * sum / kCapDirections / (e.a + e.b));
}

// A probe's mean of value(cell) over the lobe's cells where has(cell); false where none has.
template <class Has, class Value, class T>
bool lobe_mean(const LobeCells& cells, Has&& has, Value&& value, T& mean) {
  T sum{};
  float weight = 0;
  for (const auto& [cell, w] : cells) {
    if (!has(cell)) continue;
    sum += value(cell) * w;
    weight += w;
  }
  if (!(weight > 0)) return false;
  mean = sum * (1 / weight);
  return true;
}

}  // namespace penumbra::spaceland::cascade
