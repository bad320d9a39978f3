#include "view/upscale.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

using penumbra::ImageRgb;
using penumbra::Rgb;

namespace viewer {

namespace {

// The edge tests: a depth within this fraction of the pixel's own counts fully (the final
// gathers' gather_edge), beyond it less and less (1 / (1 + (dz / edge)^4)); normals by cos^8.
constexpr float kDepthEdge = 0.05f;
// An albedo below this is too dark to divide the light by.
constexpr float kDarkAlbedo = 0.02f;

float channel(const Rgb& v, int c) {
  return c == 0 ? v.r : c == 1 ? v.g : v.b;
}

constexpr float kLargest = std::numeric_limits<float>::max();

// `img` at view pixel (x, y) of a view `scale` times its size, bilinearly.
Rgb bilinear(const ImageRgb& img, int x, int y, int W, int H) {
  const int w = img.width(), h = img.height();
  const float fx = (float(x) + 0.5f) * float(w) / float(W) - 0.5f;
  const float fy = (float(y) + 0.5f) * float(h) / float(H) - 0.5f;
  const int x0 = std::clamp(int(std::floor(fx)), 0, w - 1), x1 = std::min(x0 + 1, w - 1);
  const int y0 = std::clamp(int(std::floor(fy)), 0, h - 1), y1 = std::min(y0 + 1, h - 1);
  const float tx = fx < 0 ? 0 : std::clamp(fx - std::floor(fx), 0.0f, 1.0f);
  const float ty = fy < 0 ? 0 : std::clamp(fy - std::floor(fy), 0.0f, 1.0f);
  const Rgb a = img.at(x0, y0), b = img.at(x1, y0), c = img.at(x0, y1), d = img.at(x1, y1);
  auto mix = [](const Rgb& p, const Rgb& q, float t) {
    return Rgb{p.r + (q.r - p.r) * t, p.g + (q.g - p.g) * t, p.b + (q.b - p.b) * t};
  };
  return mix(mix(a, b, tx), mix(c, d, tx), ty);
}

// The internal pixel nearest (cx, cy) within 3 pixels that saw a surface, preferring the depth
// closest to z; (cx, cy) where there is none.
std::pair<int, int> nearest_hit(const Guide& g, int cx, int cy, float z) {
  const int w = g.depth.width(), h = g.depth.height();
  std::pair<int, int> best{cx, cy};
  float best_score = INFINITY;
  for (int dy = -3; dy <= 3; ++dy)
    for (int dx = -3; dx <= 3; ++dx) {
      const int x = cx + dx, y = cy + dy;
      if (x < 0 || y < 0 || x >= w || y >= h) continue;
      const float zi = g.depth.at(x, y).r;
      if (!std::isfinite(zi)) continue;
      const float score = float(dx * dx + dy * dy) + std::fabs(zi - z) / std::max(z, 1e-20f);
      if (score < best_score) best_score = score, best = {x, y};
    }
  return best;
}

}  // namespace

Guide Guide::from(std::vector<ImageRgb> c) {
  Guide g;
  g.depth = std::move(c[0]);
  g.normal = std::move(c[1]);
  g.albedo = std::move(c[2]);
  g.emission = std::move(c[3]);
  return g;
}

ImageRgb upscale(const ImageRgb& low, const Guide& lg, const Guide& hg, bool fog) {
  const int w = low.width(), h = low.height();
  const int W = hg.depth.width(), H = hg.depth.height();
  ImageRgb out(W, H);
  tbb::parallel_for(0, H, [&](int y) {
    const float fy = (float(y) + 0.5f) * float(h) / float(H) - 0.5f;
    const int y0 = std::clamp(int(std::floor(fy)), 0, h - 1), y1 = std::min(y0 + 1, h - 1);
    const float ty = fy < 0 ? 0 : std::clamp(fy - std::floor(fy), 0.0f, 1.0f);
    for (int x = 0; x < W; ++x) {
      const Rgb le = hg.emission.at(x, y);
      const float z = hg.depth.at(x, y).r;
      if (!std::isfinite(z)) {
        // The sky (its sun included), exactly; through fog, what the internal image shows there.
        out.set(x, y, fog ? bilinear(low, x, y, W, H) : le);
        continue;
      }
      const Rgb n = hg.normal.at(x, y), a = hg.albedo.at(x, y);
      const float fx = (float(x) + 0.5f) * float(w) / float(W) - 0.5f;
      const int x0 = std::clamp(int(std::floor(fx)), 0, w - 1), x1 = std::min(x0 + 1, w - 1);
      const float tx = fx < 0 ? 0 : std::clamp(fx - std::floor(fx), 0.0f, 1.0f);
      int xs[4] = {x0, x1, x0, x1}, ys[4] = {y0, y0, y1, y1};
      const float bw[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
      float wsum = 0, nearest = INFINITY;
      int nearest_tap = -1;
      float weight[4];
      for (int i = 0; i < 4; ++i) {
        const float zi = lg.depth.at(xs[i], ys[i]).r;
        weight[i] = 0;
        if (!std::isfinite(zi)) continue;
        const float dz = std::fabs(zi - z) / std::max(z, 1e-20f);
        if (dz < nearest) nearest = dz, nearest_tap = i;
        const Rgb ni = lg.normal.at(xs[i], ys[i]);
        const float c = std::max(n.r * ni.r + n.g * ni.g + n.b * ni.b, 0.0f);
        const float c2 = c * c, c4 = c2 * c2, d = dz / kDepthEdge, d2 = d * d;
        weight[i] = (bw[i] + 1e-4f) * c4 * c4 / (1 + d2 * d2);
        wsum += weight[i];
      }
      // No tap on this surface (a thin object the internal image missed): the one nearest in
      // depth, or where every tap saw the sky, the nearest surface pixel of the internal image
      // around them.
      if (!(wsum > 1e-6f)) {
        for (float& wi : weight) wi = 0;
        if (nearest_tap < 0) {
          const auto [nx, ny] = nearest_hit(lg, (x0 + x1) / 2, (y0 + y1) / 2, z);
          xs[0] = nx;
          ys[0] = ny;
          nearest_tap = 0;
        }
        weight[nearest_tap] = 1;
        wsum = 1;
      }
      Rgb v;
      for (int c = 0; c < 3; ++c) {
        // The reflected light, divided by the albedo where every tap and the pixel can take it.
        bool divide = channel(a, c) > kDarkAlbedo;
        float sum = 0, plain = 0;
        for (int i = 0; i < 4; ++i) {
          if (weight[i] == 0) continue;
          const float ai = channel(lg.albedo.at(xs[i], ys[i]), c);
          const float r =
              channel(low.at(xs[i], ys[i]), c) - channel(lg.emission.at(xs[i], ys[i]), c);
          plain += weight[i] * r;
          if (ai > kDarkAlbedo)
            sum += weight[i] * r / ai;
          else
            divide = false;
        }
        const float reflected = divide ? channel(a, c) * sum / wsum : plain / wsum;
        // Dividing by a dark albedo can pass the float range near its top: held at its largest.
        (c == 0   ? v.r
         : c == 1 ? v.g
                  : v.b) = std::min(channel(le, c) + std::max(reflected, 0.0f), kLargest);
      }
      out.set(x, y, v);
    }
  });
  return out;
}

}  // namespace viewer
