#include "spaceland/temporal.hpp"

#include <algorithm>
#include <cmath>

#include "core/parallel.hpp"
#include "spaceland/camera.hpp"

namespace penumbra::spaceland::temporal {

double jitter(std::uint64_t frame) {
  return radical_inverse(frame, 2);
}

double radical_inverse(std::uint64_t f, unsigned base) {
  double x = 0, digit = 1.0 / base;
  for (; f; f /= base, digit /= base) x += double(f % base) * digit;
  return x;
}

std::uint64_t History::bytes() const {
  return value.size() * kBytesPerPixel;
}

namespace {

// The albedo divided out of a pixel, per channel: 1 where it is too dark to divide by.
Rgb modulation(const Rgb& a) {
  const auto m = [](float c) { return c >= kMinAlbedo ? c : 1.0f; };
  return {m(a.r), m(a.g), m(a.b)};
}

// Where a world point lands in the previous frame: its pixel coordinates (pixel centres at
// integers) and linear depth; false behind the camera.
struct Projection {
  Vec3 eye, f, r, u;
  double sx = 1, sy = 1;  // pixels per unit of the image plane at depth 1
  int width = 0, height = 0;

  explicit Projection(const Camera& c) {
    const CameraRays rays(c);
    eye = rays.origin();
    f = rays.forward();
    r = rays.right();
    u = rays.up();
    width = c.width;
    height = c.height;
    const double t = rays.tan_half_fov();
    sx = width / (2 * t * width / height);
    sy = height / (2 * t);
  }
  bool operator()(Vec3 p, double& x, double& y, float& depth) const {
    const Vec3 v = p - eye;
    depth = dot(v, f);
    if (!(depth > 0)) return false;
    x = double(dot(v, r)) / depth * sx + width / 2.0 - 0.5;
    y = -double(dot(v, u)) / depth * sy + height / 2.0 - 0.5;
    return std::isfinite(x) && std::isfinite(y);
  }
};

}  // namespace

void accumulate(const Scene& scene, const GBuffer& g, const Exact& exact_part, int frames,
                ImageRgb& image, History& h) {
  const std::size_t n = std::size_t(g.width) * g.height;
  const bool have = h.frame > 0 && !h.value.empty();
  // A method that reports no exact part has all of its light blended, undivided.
  const bool reported = exact_part.light.size() == n && exact_part.albedo.size() == n;
  const Projection previous(h.camera);
  std::vector<Rgb> value(n);
  std::vector<float> depth(n, -1.0f), count(n, 0.0f);
  std::vector<Vec3> normal(n);
  std::vector<std::uint32_t> material(n, 0);
  parallel_for(g.height, [&](int j) {
    for (int i = 0; i < g.width; ++i) {
      const std::size_t k = std::size_t(j) * g.width + i;
      if (!g.found[k]) continue;  // the sky: exact in every frame
      const Hit& hit = g.hits[k];
      const Rgb m = reported ? modulation(exact_part.albedo[k]) : Rgb{1, 1, 1};
      const Rgb exact = reported ? exact_part.light[k] : Rgb{};
      const Rgb c = image.at(i, j);
      const Rgb now{(c.r - exact.r) / m.r, (c.g - exact.g) / m.g, (c.b - exact.b) / m.b};
      depth[k] = g.linear_depth(k);
      normal[k] = hit.shading_normal;
      material[k] = hit.material;
      Rgb past{};
      float frames_past = 0, weight = 0;
      double x = 0, y = 0;
      float z = 0;
      if (have && previous(hit.position, x, y, z)) {
        // Bilinear over the 4 history pixels around it, each only where it saw the same surface.
        const double fx = std::floor(x), fy = std::floor(y);
        const int x0 = int(fx), y0 = int(fy);
        const float ax = float(x - fx), ay = float(y - fy);
        for (int t = 0; t < 4; ++t) {
          const int px = x0 + (t & 1), py = y0 + (t >> 1);
          if (px < 0 || py < 0 || px >= previous.width || py >= previous.height) continue;
          const std::size_t q = std::size_t(py) * previous.width + px;
          const float d = h.depth[q];
          if (d < 0 || h.material[q] != hit.material || std::abs(d - z) > kDepthEdge * z) continue;
          if (dot(h.normal[q], hit.shading_normal) < kNormalEdge) continue;
          const float w = ((t & 1) ? ax : 1 - ax) * ((t >> 1) ? ay : 1 - ay);
          if (w <= 0) continue;
          past.r += w * h.value[q].r;
          past.g += w * h.value[q].g;
          past.b += w * h.value[q].b;
          frames_past += w * h.count[q];
          weight += w;
        }
      }
      value[k] = now;
      count[k] = 1;
      // A history from less than a tenth of its footprint is an edge's: the frame alone, as it is.
      if (weight <= 0.1f) continue;
      const float kept = std::min(frames_past / weight + 1, float(frames)), a = 1 / kept;
      const Rgb v{past.r / weight + a * (now.r - past.r / weight),
                  past.g / weight + a * (now.g - past.g / weight),
                  past.b / weight + a * (now.b - past.b / weight)};
      value[k] = v;
      count[k] = kept;
      image.set(i, j, {exact.r + v.r * m.r, exact.g + v.g * m.g, exact.b + v.b * m.b});
    }
  });
  h.value = std::move(value);
  h.depth = std::move(depth);
  h.normal = std::move(normal);
  h.material = std::move(material);
  h.count = std::move(count);
  h.camera = scene.camera;
  h.sun = scene.sun;
  h.sky = scene.sky;
  ++h.frame;
}

}  // namespace penumbra::spaceland::temporal
