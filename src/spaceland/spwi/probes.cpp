#include "spaceland/spwi/probes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.hpp"

namespace penumbra::spaceland::spwi {

double tile_centre(int k, int spacing) {
  return double(k) * spacing + spacing / 2 + 0.5;
}

namespace {

// The 4 tiles of a cascade around the screen point (x, y) and their bilinear weights, corners in
// the order (0, 0), (1, 0), (0, 1), (1, 1) (Alg. 8's srcPoints order); fx, fy the point's place
// between them.
Corners screen_corners(double x, double y, int spacing, int nx, int ny, float& fx, float& fy) {
  auto axis = [&](double c, int n, int& base, float& f) {
    const double g = (c - (spacing / 2 + 0.5)) / spacing;
    base = int(std::floor(g));
    f = float(g - base);
    if (n == 1) {
      base = 0;
      f = 0;
    } else if (base < 0) {
      base = 0;
      f = 0;
    } else if (base >= n - 1) {
      base = n - 2;
      f = 1;
    }
  };
  int bx, by;
  axis(x, nx, bx, fx);
  axis(y, ny, by, fy);
  const int bx1 = std::min(bx + 1, nx - 1), by1 = std::min(by + 1, ny - 1);
  Corners c;
  c.index = {std::uint64_t(by * nx + bx), std::uint64_t(by * nx + bx1),
             std::uint64_t(by1 * nx + bx), std::uint64_t(by1 * nx + bx1)};
  c.w = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
  c.n = 4;
  return c;
}

const Probe& probe_of(const std::vector<Probe>& probes, const Corners& c, int k) {
  return probes[std::size_t(c.index[std::size_t(k)])];
}

// Bilateral weighting (seed 000 Alg. 7 and 11): on a depth edge among the valid probes (their
// depth range over their mean above `edge`), each weight is divided by the probe's depth
// difference to the point.
void bilateral(Corners& c, const std::vector<Probe>& probes, float depth, float edge) {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo, sum = 0;
  int n = 0;
  for (int k = 0; k < c.n; ++k) {
    if (c.w[std::size_t(k)] <= 0) continue;
    const float d = probe_of(probes, c, k).depth;
    lo = std::min(lo, d);
    hi = std::max(hi, d);
    sum += d;
    ++n;
  }
  if (n < 2 || !((hi - lo) / (sum / float(n)) > edge)) return;
  for (int k = 0; k < c.n; ++k) {
    if (c.w[std::size_t(k)] <= 0) continue;
    c.w[std::size_t(k)] /= std::abs(probe_of(probes, c, k).depth - depth) + 1e-4f;
  }
}

// Where the projection of p falls along the line a -> b, as a fraction in [0, 1].
float project(Vec3 a, Vec3 b, Vec3 p) {
  const Vec3 ab = b - a;
  const float len2 = dot(ab, ab);
  if (!(len2 > 0)) return 0.5f;
  return std::clamp(dot(p - a, ab) / len2, 0.0f, 1.0f);
}

Vec3 mix(Vec3 a, Vec3 b, float t) {
  return a + (b - a) * t;
}

// Seed 000 Alg. 8: the bilinear ratios refined by projecting the point onto the lines between
// the 4 probes in world space (two iterations), starting from the screen-space ratios.
void bilinear3d(Corners& c, const std::vector<Probe>& probes, Vec3 point, float fx, float fy) {
  const Vec3 s[4] = {probe_of(probes, c, 0).p, probe_of(probes, c, 1).p, probe_of(probes, c, 2).p,
                     probe_of(probes, c, 3).p};
  float rx = fx, ry = fy;
  for (int it = 0; it < 2; ++it) {
    rx = project(mix(s[0], s[2], ry), mix(s[1], s[3], ry), point);
    ry = project(mix(s[0], s[1], rx), mix(s[2], s[3], rx), point);
  }
  c.w = {(1 - rx) * (1 - ry), rx * (1 - ry), (1 - rx) * ry, rx * ry};
}

// Zero weights of probes on the sky, then normalise; false when no probe is left.
bool normalise(Corners& c, const std::vector<Probe>& probes) {
  float sum = 0;
  for (int k = 0; k < c.n; ++k) {
    if (!probe_of(probes, c, k).valid) c.w[std::size_t(k)] = 0;
    sum += c.w[std::size_t(k)];
  }
  if (!(sum > 0)) return false;
  for (int k = 0; k < c.n; ++k) c.w[std::size_t(k)] /= sum;
  return true;
}

// Screen corners with sky probes left out before the depth weights look at them.
Corners valid_corners(double x, double y, int spacing, int nx, int ny,
                      const std::vector<Probe>& probes, float& fx, float& fy) {
  Corners c = screen_corners(x, y, spacing, nx, ny, fx, fy);
  for (int k = 0; k < 4; ++k)
    if (!probe_of(probes, c, k).valid) c.w[std::size_t(k)] = 0;
  return c;
}

// The min-max merge (seed 000 chapter 7): each tile has a probe on the nearest and one on the
// farthest surface in it; a point at `depth` takes each tile's two by linear interpolation in
// depth between them (trilinear with the screen's bilinear weights). `c` holds tile indices;
// probes are 2 per tile (min, max).
Corners minmax_corners(const Corners& c, const std::vector<Probe>& probes, float depth) {
  Corners out;
  for (int k = 0; k < 4; ++k) {
    const float w = c.w[std::size_t(k)];
    if (w <= 0) continue;
    const std::uint64_t lo = 2 * c.index[std::size_t(k)], hi = lo + 1;
    const Probe &a = probes[std::size_t(lo)], &b = probes[std::size_t(hi)];
    if (!a.valid && !b.valid) continue;
    float t = 0.5f;
    if (a.valid && b.valid) {
      const float span = b.depth - a.depth;
      t = span > 0 ? std::clamp((depth - a.depth) / span, 0.0f, 1.0f) : 0.5f;
    } else {
      t = b.valid ? 1.0f : 0.0f;
    }
    out.index[std::size_t(out.n)] = lo;
    out.w[std::size_t(out.n++)] = w * (1 - t);
    out.index[std::size_t(out.n)] = hi;
    out.w[std::size_t(out.n++)] = w * t;
  }
  if (out.n == 0) {  // no tile with a surface: an entry of weight 0 that normalise refuses
    out.n = 1;
    out.index[0] = 2 * c.index[0];
    out.w[0] = 0;
  }
  return out;
}

// A probe on the surface pixel (x, y) sees, if it sees one.
Probe probe_at(const Scene& scene, const GBuffer& g, int x, int y, float depth_bias) {
  Probe p;
  x = std::clamp(x, 0, g.width - 1);
  y = std::clamp(y, 0, g.height - 1);
  const std::size_t k = std::size_t(y) * g.width + x;
  if (!g.found[k]) return p;
  const Hit& h = g.hits[k];
  const Vec3 eye = scene.camera.position;
  p.valid = true;
  p.p = eye + (h.position - eye) * depth_bias;
  p.n = h.geometric_normal;
  p.depth = g.linear_depth(k);
  return p;
}

// With the min-max merge: per tile, probes on the nearest and the farthest surface pixel of the
// tile (the min-max depth pyramid's level of this cascade, read directly off the G-buffer).
std::vector<Probe> place_minmax_probes(const Scene& scene, const GBuffer& g, const Layout& layout,
                                       int i, float depth_bias) {
  const int s = layout.spacing(i), nx = layout.nx[std::size_t(i)], ny = layout.ny[std::size_t(i)];
  std::vector<Probe> probes(std::size_t(nx) * ny * 2);
  parallel_for(ny, [&](int ty) {
    for (int tx = 0; tx < nx; ++tx) {
      float lo = std::numeric_limits<float>::infinity(), hi = -lo;
      int lx = -1, ly = -1, hx = -1, hy = -1;
      const int x0 = tx * s + layout.shift_x, y0 = ty * s + layout.shift_y;
      for (int y = std::max(y0, 0); y < std::min(y0 + s, g.height); ++y)
        for (int x = std::max(x0, 0); x < std::min(x0 + s, g.width); ++x) {
          const std::size_t k = std::size_t(y) * g.width + x;
          if (!g.found[k]) continue;
          const float d = g.linear_depth(k);
          if (d < lo) lo = d, lx = x, ly = y;
          if (d > hi) hi = d, hx = x, hy = y;
        }
      const std::size_t t = std::size_t(ty) * nx + tx;
      if (lx < 0) continue;
      probes[2 * t] = probe_at(scene, g, lx, ly, depth_bias);
      probes[2 * t + 1] = probe_at(scene, g, hx, hy, depth_bias);
    }
  });
  return probes;
}

}  // namespace

std::vector<Probe> place_probes(const Scene& scene, const GBuffer& g, const Layout& layout, int i,
                                const SpwiOptions& o) {
  if (o.merge == SpwiMerge::minmax) return place_minmax_probes(scene, g, layout, i, o.depth_bias);
  const int s = layout.spacing(i), nx = layout.nx[std::size_t(i)], ny = layout.ny[std::size_t(i)];
  std::vector<Probe> probes(std::size_t(nx) * ny);
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x)
      probes[std::size_t(y) * nx + x] = probe_at(scene, g, x * s + s / 2 + layout.shift_x,
                                                 y * s + s / 2 + layout.shift_y, o.depth_bias);
  return probes;
}

std::vector<std::array<Probe, 4>> place_sub_probes(const Scene& scene, const GBuffer& g,
                                                   const Layout& layout, int i, float depth_bias) {
  const int s = layout.spacing(i), nx = layout.nx[std::size_t(i)], ny = layout.ny[std::size_t(i)];
  const int q1 = s / 4, q3 = (3 * s) / 4, dx = layout.shift_x, dy = layout.shift_y;
  std::vector<std::array<Probe, 4>> subs(std::size_t(nx) * ny);
  for (int y = 0; y < ny; ++y)
    for (int x = 0; x < nx; ++x) {
      std::array<Probe, 4>& sp = subs[std::size_t(y) * nx + x];
      sp[0] = probe_at(scene, g, x * s + q1 + dx, y * s + q1 + dy, depth_bias);
      sp[1] = probe_at(scene, g, x * s + q3 + dx, y * s + q1 + dy, depth_bias);
      sp[2] = probe_at(scene, g, x * s + q1 + dx, y * s + q3 + dy, depth_bias);
      sp[3] = probe_at(scene, g, x * s + q3 + dx, y * s + q3 + dy, depth_bias);
    }
  return subs;
}

bool upper_corners(const Layout& layout, int up, double x, double y, const Probe& probe,
                   const std::vector<Probe>& upper, const SpwiOptions& o, Corners& c) {
  const int spacing = layout.spacing(up), nx = layout.nx[std::size_t(up)],
            ny = layout.ny[std::size_t(up)];
  float fx = 0, fy = 0;
  // The lattice's own coordinates: its shift taken off.
  x -= layout.shift_x;
  y -= layout.shift_y;
  if (o.merge == SpwiMerge::minmax) {
    c = minmax_corners(screen_corners(x, y, spacing, nx, ny, fx, fy), upper, probe.depth);
    return normalise(c, upper);
  }
  c = valid_corners(x, y, spacing, nx, ny, upper, fx, fy);
  // The fix weighs its 4 segments as the bilateral merge weighs probes: a probe across a depth
  // edge would send the segment through whatever lies between.
  if (o.merge == SpwiMerge::bilateral || o.merge == SpwiMerge::fix)
    bilateral(c, upper, probe.depth, o.merge_edge);
  if (o.merge == SpwiMerge::bilinear3d) bilinear3d(c, upper, probe.p, fx, fy);
  return normalise(c, upper);
}

bool gather_corners(const Layout& layout, int i, int x, int y, float depth, Vec3 normal,
                    const std::vector<Probe>& probes, const SpwiOptions& o, Corners& c) {
  float fx = 0, fy = 0;
  const int s = layout.spacing(i), nx = layout.nx[std::size_t(i)], ny = layout.ny[std::size_t(i)];
  // The pixel's centre in the lattice's own coordinates.
  const double cx = x + 0.5 - layout.shift_x, cy = y + 0.5 - layout.shift_y;
  if (o.merge == SpwiMerge::minmax) {
    c = minmax_corners(screen_corners(cx, cy, s, nx, ny, fx, fy), probes, depth);
  } else {
    c = valid_corners(cx, cy, s, nx, ny, probes, fx, fy);
    bilateral(c, probes, depth, o.gather_edge);
  }
  if (o.gather_normal > 0) {
    // Probes on surfaces facing elsewhere (the front of a block, for a pixel on its top) gather
    // light the pixel does not see: weighted by cos^p of the normals' angle, unless that leaves
    // no probe.
    Corners facing = c;
    float left = 0;
    for (int j = 0; j < c.n; ++j) {
      facing.w[std::size_t(j)] *=
          std::pow(std::max(0.0f, dot(probe_of(probes, c, j).n, normal)), o.gather_normal);
      left += facing.w[std::size_t(j)];
    }
    if (left > 0) c = facing;
  }
  return normalise(c, probes);
}

}  // namespace penumbra::spaceland::spwi
