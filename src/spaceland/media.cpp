#include "spaceland/media.hpp"

#include <algorithm>
#include <cmath>

#include "spaceland/color.hpp"

namespace penumbra::spaceland {

namespace {

// [t0, t1] of the ray inside the box, clipped to [0, tmax]; false when it misses.
bool box_span(const Medium& m, const Ray& ray, float tmax, float& t0, float& t1) {
  double lo = 0, hi = tmax;
  const Vec3 o = ray.origin - m.center;
  for (int a = 0; a < 3; ++a) {
    const double oa = dot(o, m.axes[a]), da = dot(ray.direction, m.axes[a]);
    const double h = m.half_size[a];
    if (da == 0) {
      if (oa < -h || oa > h) return false;
      continue;
    }
    double ta = (-h - oa) / da, tb = (h - oa) / da;
    if (ta > tb) std::swap(ta, tb);
    lo = std::max(lo, ta);
    hi = std::min(hi, tb);
    if (lo >= hi) return false;
  }
  t0 = float(lo);
  t1 = float(hi);
  return t1 > t0;
}

}  // namespace

void Media::pieces(const Ray& ray, float tmax, std::vector<MediumPiece>& out) const {
  out.clear();
  // Breakpoints are where a box starts or ends; between two, the coefficients are constant.
  thread_local std::vector<float> cuts;
  thread_local std::vector<std::pair<float, float>> spans;
  cuts.clear();
  spans.assign(media_->size(), {0.0f, 0.0f});
  for (std::size_t i = 0; i < media_->size(); ++i) {
    float t0, t1;
    if (!box_span((*media_)[i], ray, tmax, t0, t1)) {
      spans[i] = {1.0f, 0.0f};  // empty
      continue;
    }
    spans[i] = {t0, t1};
    cuts.push_back(t0);
    cuts.push_back(t1);
  }
  std::sort(cuts.begin(), cuts.end());
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    const float a = cuts[k], b = cuts[k + 1];
    if (!(b > a)) continue;
    const float mid = 0.5f * (a + b);
    MediumPiece p{a, b, {}, {}, {}};
    bool any = false;
    for (std::size_t i = 0; i < media_->size(); ++i) {
      if (!(spans[i].first <= mid && mid <= spans[i].second)) continue;
      const Medium& m = (*media_)[i];
      p.sigma_t += m.extinction;
      p.sigma_s += m.extinction * m.albedo;
      p.emission += m.emission;
      any = true;
    }
    if (any) out.push_back(p);
  }
}

Rgb Media::transmittance(const Ray& ray, float tmax) const {
  Rgb tau{};
  for (const Medium& m : *media_) {
    float t0, t1;
    if (box_span(m, ray, tmax, t0, t1)) tau += m.extinction * (t1 - t0);
  }
  return exp_neg(tau);
}

Rgb Media::emitted(const std::vector<MediumPiece>& pieces) {
  Rgb sum{}, tau{};
  for (const MediumPiece& p : pieces) {
    const float len = p.t1 - p.t0;
    const Rgb t0 = exp_neg(tau);
    for (int c = 0; c < 3; ++c) {
      const double s = channel(p.sigma_t, c), e = channel(p.emission, c);
      // integral over the stretch of exp(-s x) e dx, from its start
      const double part = s > 0 ? e * -std::expm1(-s * len) / s : e * len;
      (c == 0 ? sum.r : c == 1 ? sum.g : sum.b) += float(channel(t0, c) * part);
    }
    tau += p.sigma_t * len;
  }
  return sum;
}

FreeFlight Media::sample(const std::vector<MediumPiece>& pieces, float u_channel, float u) {
  FreeFlight f;
  const int c = std::min(2, int(u_channel * 3));
  double remaining = -std::log1p(-double(u));  // optical depth to travel in channel c
  Rgb tau{};
  for (const MediumPiece& p : pieces) {
    const double len = p.t1 - p.t0, s = channel(p.sigma_t, c);
    if (s * len > remaining) {
      const double dt = remaining / s;
      const Rgb tr = exp_neg(tau + p.sigma_t * float(dt));
      // The density of scattering here, averaged over the three channels' sampling.
      const double pdf =
          (double(p.sigma_t.r) * tr.r + double(p.sigma_t.g) * tr.g + double(p.sigma_t.b) * tr.b) /
          3;
      f.scattered = true;
      f.t = float(p.t0 + dt);
      f.weight = pdf > 0 ? tr * p.sigma_s * float(1 / pdf) : Rgb{};
      return f;
    }
    remaining -= s * len;
    tau += p.sigma_t * float(len);
  }
  const Rgb tr = exp_neg(tau);
  const double pass = (double(tr.r) + tr.g + tr.b) / 3;
  f.weight = pass > 0 ? tr * float(1 / pass) : Rgb{};
  return f;
}

}  // namespace penumbra::spaceland
