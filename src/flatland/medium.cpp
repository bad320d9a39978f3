#include "flatland/medium.hpp"

#include <algorithm>
#include <cmath>

#include "core/parallel.hpp"

namespace penumbra::flatland {

float extinction(float opacity) {
  if (opacity >= 1.0f) return kOpaque;
  if (opacity <= 0.0f) return 0.0f;
  return -std::log1p(-opacity);
}

void fill_medium(const Scene& scene, Medium& m) {
  m.width = scene.width;
  m.height = scene.height;
  m.cells.resize(scene.cells());
  m.step.resize(scene.cells());
  m.blocks_x = m.blocks_y = 0;  // blocks of an earlier scene are void
  m.block_empty.clear();
  const std::vector<float>& le = scene.emission;
  parallel_for(scene.height, [&](int y) {
    for (int x = 0; x < scene.width; ++x) {
      const std::size_t i = scene.index(x, y);
      m.cells[i] = {le[3 * i], le[3 * i + 1], le[3 * i + 2]};
      m.step[i] = extinction(scene.opacity[i]);
    }
  });
}

Medium make_medium(const Scene& scene) {
  Medium m;
  fill_medium(scene, m);
  return m;
}

std::uint64_t distance_field_bytes(int width, int height) {
  return std::uint64_t(width) * height * (sizeof(float) + 2 * sizeof(std::int32_t));
}

std::vector<int> jump_flood_steps(int width, int height) {
  int top = 1;
  while (top * 2 < std::max(width, height)) top *= 2;
  std::vector<int> steps;
  for (int s = top; s >= 1; s /= 2) steps.push_back(s);
  steps.push_back(2);
  steps.push_back(1);
  return steps;
}

std::vector<float> jump_flood_distance(const Medium& m) {
  const int w = m.width, h = m.height;
  const std::size_t n = std::size_t(w) * h;
  // Each cell holds the index of the nearest seed found so far, -1 for none.
  std::vector<std::int32_t> a(n), b(n);
  parallel_for(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      a[i] = m.step[i] > 0 ? std::int32_t(i) : -1;
    }
  });
  auto dist2 = [w](int x, int y, std::int32_t s) {
    const float dx = float(s % w - x), dy = float(s / w - y);
    return dx * dx + dy * dy;
  };
  auto pass = [&](const std::vector<std::int32_t>& in, std::vector<std::int32_t>& out, int step) {
    parallel_for(h, [&](int y) {
      for (int x = 0; x < w; ++x) {
        std::int32_t best = in[std::size_t(y) * w + x];
        float best_d = best >= 0 ? dist2(x, y, best) : std::numeric_limits<float>::infinity();
        for (int oy = -step; oy <= step; oy += step) {
          const int sy = y + oy;
          if (sy < 0 || sy >= h) continue;
          for (int ox = -step; ox <= step; ox += step) {
            const int sx = x + ox;
            if (sx < 0 || sx >= w || (ox == 0 && oy == 0)) continue;
            const std::int32_t s = in[std::size_t(sy) * w + sx];
            if (s < 0) continue;
            const float d = dist2(x, y, s);
            // Ties go to the lower index so the result does not depend on visiting order.
            if (d < best_d || (d == best_d && s < best)) best = s, best_d = d;
          }
        }
        out[std::size_t(y) * w + x] = best;
      }
    });
  };
  for (int s : jump_flood_steps(w, h)) {
    pass(a, b, s);
    std::swap(a, b);
  }
  std::vector<float> distance(n);
  parallel_for(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      distance[i] =
          a[i] >= 0 ? std::sqrt(dist2(x, y, a[i])) : std::numeric_limits<float>::infinity();
    }
  });
  return distance;
}

void build_distance_field(Medium& m) {
  const std::vector<float> distance = jump_flood_distance(m);
  parallel_for(m.height, [&](int y) {
    for (int x = 0; x < m.width; ++x) {
      const std::size_t i = std::size_t(y) * m.width + x;
      // A jump from anywhere in this cell stays in empty cells for distance - sqrt(2) (half a
      // diagonal at each end); the extra half cell absorbs JFA's rare inexact answers. Short
      // jumps save less than plain cell stepping costs.
      const float jump = distance[i] - (1.4142136f + 0.5f);
      if (m.step[i] <= 0) m.step[i] = jump > 2.0f ? -jump : 0.0f;
    }
  });
}

std::uint64_t blocks_bytes(int width, int height) {
  return std::uint64_t((width + 7) >> kBlockShift) * ((height + 7) >> kBlockShift);
}

void build_blocks(Medium& m) {
  m.blocks_x = (m.width + 7) >> kBlockShift;
  m.blocks_y = (m.height + 7) >> kBlockShift;
  m.block_empty.assign(std::size_t(m.blocks_x) * m.blocks_y, 1);
  parallel_for(m.blocks_y, [&](int by) {
    const int y1 = std::min((by + 1) << kBlockShift, m.height);
    for (int y = by << kBlockShift; y < y1; ++y)
      for (int x = 0; x < m.width; ++x)
        if (m.step[std::size_t(y) * m.width + x] > 0)
          m.block_empty[std::size_t(by) * m.blocks_x + (x >> kBlockShift)] = 0;
  });
}

}  // namespace penumbra::flatland
