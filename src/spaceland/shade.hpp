// Shading the camera's visible pixels in parallel rows, the sky where a pixel sees none.
#pragma once

#include <atomic>
#include <cstdint>

#include "core/parallel.hpp"
#include "penumbra/image.hpp"
#include "spaceland/gbuffer.hpp"
#include "spaceland/sky.hpp"

namespace penumbra::spaceland {

// The camera's image shaded in parallel rows: a pixel that sees the sky shows `bg`, one that
// hits a surface shade(x, y, k, hit, rays) (k = y * width + x; `rays` counts the rays the
// shading traces, added to `traced`).
template <class Shade>
ImageRgb shade_pixels(const GBuffer& g, const Background& bg, std::uint64_t& traced,
                      Shade&& shade) {
  ImageRgb img(g.width, g.height);
  std::atomic<std::uint64_t> count{0};
  parallel_for(g.height, [&](int y) {
    std::uint64_t local = 0;
    for (int x = 0; x < g.width; ++x) {
      const std::size_t k = std::size_t(y) * std::size_t(g.width) + std::size_t(x);
      img.set(x, y, g.found[k] ? shade(x, y, k, g.hits[k], local) : bg(g.directions[k]));
    }
    count.fetch_add(local, std::memory_order_relaxed);
  });
  traced += count.load();
  return img;
}

}  // namespace penumbra::spaceland
