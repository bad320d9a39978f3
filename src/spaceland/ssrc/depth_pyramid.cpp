#include "spaceland/ssrc/depth_pyramid.hpp"

#include <algorithm>
#include <limits>

#include "core/huge_pages.hpp"
#include "core/parallel.hpp"

namespace penumbra::spaceland::ssrc {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// The level sizes from width x height down to 1 x 1.
template <class Visit>
void for_each_size(int width, int height, Visit&& visit) {
  int w = width, h = height;
  for (;;) {
    visit(w, h);
    if (w == 1 && h == 1) break;
    w = (w + 1) / 2, h = (h + 1) / 2;
  }
}

}  // namespace

std::uint64_t DepthPyramid::bytes(int width, int height) {
  std::uint64_t texels = 0;
  for_each_size(width, height,
                [&](int w, int h) { texels += std::uint64_t(w) * std::uint64_t(h); });
  return texels * 2 * sizeof(float);
}

DepthPyramid DepthPyramid::build(const GBuffer& g) {
  DepthPyramid p;
  if (g.width < 1 || g.height < 1) return p;
  for_each_size(g.width, g.height, [&](int w, int h) {
    Level l;
    l.width = w, l.height = h;
    assign_huge(l.lo, std::size_t(w) * std::size_t(h));
    assign_huge(l.hi, l.lo.size());
    p.levels_.push_back(std::move(l));
  });
  Level& base = p.levels_[0];
  parallel_for(g.height, [&](int y) {
    for (int x = 0; x < g.width; ++x) {
      const std::size_t k = std::size_t(y) * std::size_t(g.width) + std::size_t(x);
      const bool hit = g.found[k];
      base.lo[k] = hit ? g.linear_depth(k) : kInf;
      base.hi[k] = hit ? g.linear_depth(k) : -kInf;
    }
  });
  for (std::size_t l = 1; l < p.levels_.size(); ++l) {
    const Level& below = p.levels_[l - 1];
    Level& at = p.levels_[l];
    parallel_for(at.height, [&](int y) {
      for (int x = 0; x < at.width; ++x) {
        float lo = kInf, hi = -kInf;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int bx = 2 * x + dx, by = 2 * y + dy;
            if (bx >= below.width || by >= below.height) continue;  // past an odd edge
            const std::size_t k = std::size_t(by) * std::size_t(below.width) + std::size_t(bx);
            lo = std::min(lo, below.lo[k]);
            hi = std::max(hi, below.hi[k]);
          }
        const std::size_t k = std::size_t(y) * std::size_t(at.width) + std::size_t(x);
        at.lo[k] = lo;
        at.hi[k] = hi;
      }
    });
  }
  return p;
}

}  // namespace penumbra::spaceland::ssrc
