// Sampling a texture at texture coordinates: glTF's wrap modes, nearest or bilinear.
#include <algorithm>
#include <cmath>

#include "spaceland/scene/mesh_file.hpp"

namespace penumbra::spaceland {

namespace {

// Texel index along one axis for coordinate index i (may be outside [0, n)).
int wrap_index(int i, int n, Texture::Wrap wrap) {
  switch (wrap) {
    case Texture::Wrap::clamp:
      return std::clamp(i, 0, n - 1);
    case Texture::Wrap::mirror: {
      const int period = 2 * n;
      int k = i % period;
      if (k < 0) k += period;
      return k < n ? k : period - 1 - k;
    }
    case Texture::Wrap::repeat:
    default: {
      int k = i % n;
      return k < 0 ? k + n : k;
    }
  }
}

Rgb texel(const Texture& t, int x, int y) {
  const float* p = &t.rgb[(std::size_t(y) * t.width + x) * 3];
  return {p[0], p[1], p[2]};
}

}  // namespace

Rgb sample_texture(const Texture& t, float u, float v) {
  if (t.width <= 0 || t.height <= 0 || !std::isfinite(u) || !std::isfinite(v)) return {0, 0, 0};
  // Texel centres sit at (i + 0.5) / width. Coordinates are reduced first so that huge values
  // do not overflow the texel index.
  const double fu = double(u) - (t.wrap_s == Texture::Wrap::clamp ? 0 : std::floor(u / 2.0) * 2);
  const double fv = double(v) - (t.wrap_t == Texture::Wrap::clamp ? 0 : std::floor(v / 2.0) * 2);
  const double x = std::clamp(fu * t.width - 0.5, -2.0 * t.width, 4.0 * t.width);
  const double y = std::clamp(fv * t.height - 0.5, -2.0 * t.height, 4.0 * t.height);
  if (t.nearest) {
    const int ix = wrap_index(int(std::floor(x + 0.5)), t.width, t.wrap_s);
    const int iy = wrap_index(int(std::floor(y + 0.5)), t.height, t.wrap_t);
    return texel(t, ix, iy);
  }
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  const float ax = float(x - x0), ay = float(y - y0);
  const int xa = wrap_index(x0, t.width, t.wrap_s), xb = wrap_index(x0 + 1, t.width, t.wrap_s);
  const int ya = wrap_index(y0, t.height, t.wrap_t), yb = wrap_index(y0 + 1, t.height, t.wrap_t);
  const Rgb c00 = texel(t, xa, ya), c10 = texel(t, xb, ya), c01 = texel(t, xa, yb),
            c11 = texel(t, xb, yb);
  auto mix = [&](float a, float b, float c, float d) {
    return (a * (1 - ax) + b * ax) * (1 - ay) + (c * (1 - ax) + d * ax) * ay;
  };
  return {mix(c00.r, c10.r, c01.r, c11.r), mix(c00.g, c10.g, c01.g, c11.g),
          mix(c00.b, c10.b, c01.b, c11.b)};
}

}  // namespace penumbra::spaceland
