#include "spaceland/ssrc/ssrc.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <experimental/simd>
#include <limits>
#include <string>
#include <vector>

#include "core/huge_pages.hpp"
#include "core/math.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "io/json_reader.hpp"
#include "spaceland/brdf_albedo.hpp"
#include "spaceland/camera.hpp"
#include "spaceland/cascade/cone.hpp"
#include "spaceland/radiance_cache.hpp"
#include "spaceland/shade.hpp"
#include "spaceland/sky.hpp"
#include "spaceland/spwi/probes.hpp"
#include "spaceland/ssrc/depth_pyramid.hpp"
#include "spaceland/sun.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland::ssrc {

namespace {

bool power_of_two(int v) {
  return v > 0 && (v & (v - 1)) == 0;
}

// The per-level means the march reads besides the depth pyramid: the mean position and
// radiance of the hits under each texel, and how many there are (0: only misses).
struct Means {
  struct Level {
    int width = 0, height = 0;
    std::vector<Vec3> position, normal;  // normal: the mean of unit normals (not unit)
    std::vector<Rgb> radiance;
    // The depth where the solid behind the hits ends, over theirs (>= 1): the mean over them.
    std::vector<float> grow;
    std::vector<float> count;
  };
  std::vector<Level> levels;

  static std::uint64_t bytes_per_texel() {
    return 2 * sizeof(Vec3) + sizeof(Rgb) + 2 * sizeof(float);
  }
};

// The levels' positions, normals, solids and counts (the radiance comes per bounce), sized as the
// depth pyramid; `grow`, per pixel, where its solid ends over its depth.
Means make_means(const GBuffer& g, const DepthPyramid& depth, const std::vector<float>& grow) {
  Means m;
  for (int l = 0; l < depth.levels(); ++l) {
    Means::Level at;
    at.width = depth.level(l).width;
    at.height = depth.level(l).height;
    const std::size_t n = std::size_t(at.width) * std::size_t(at.height);
    assign_huge(at.position, n);
    assign_huge(at.normal, n);
    assign_huge(at.grow, n, 1.0f);
    assign_huge(at.radiance, n);
    assign_huge(at.count, n);
    m.levels.push_back(std::move(at));
  }
  Means::Level& base = m.levels[0];
  parallel_for(g.height, [&](int y) {
    for (int x = 0; x < g.width; ++x) {
      const std::size_t k = std::size_t(y) * std::size_t(g.width) + std::size_t(x);
      if (!g.found[k]) continue;
      base.position[k] = g.hits[k].position;
      base.normal[k] = g.hits[k].geometric_normal;
      base.grow[k] = grow[k];
      base.count[k] = 1;
    }
  });
  for (std::size_t l = 1; l < m.levels.size(); ++l) {
    const Means::Level& below = m.levels[l - 1];
    Means::Level& at = m.levels[l];
    parallel_for(at.height, [&](int y) {
      for (int x = 0; x < at.width; ++x) {
        Vec3 sum{}, normal{};
        float n = 0, solid = 0;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int bx = 2 * x + dx, by = 2 * y + dy;
            if (bx >= below.width || by >= below.height) continue;
            const std::size_t k = std::size_t(by) * std::size_t(below.width) + std::size_t(bx);
            sum = sum + below.position[k] * below.count[k];
            normal = normal + below.normal[k] * below.count[k];
            solid += below.grow[k] * below.count[k];
            n += below.count[k];
          }
        const std::size_t k = std::size_t(y) * std::size_t(at.width) + std::size_t(x);
        at.count[k] = n;
        at.position[k] = n > 0 ? sum * (1 / n) : Vec3{};
        at.normal[k] = n > 0 ? normal * (1 / n) : Vec3{};
        at.grow[k] = n > 0 ? solid / n : 1.0f;
      }
    });
  }
  return m;
}

// The radiance leaving each visible pixel (level 0) and its means over the levels.
void fill_radiance(Means& m, const std::vector<Rgb>& pixels) {
  m.levels[0].radiance = pixels;
  for (std::size_t l = 1; l < m.levels.size(); ++l) {
    const Means::Level& below = m.levels[l - 1];
    Means::Level& at = m.levels[l];
    parallel_for(at.height, [&](int y) {
      for (int x = 0; x < at.width; ++x) {
        Rgb sum{};
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int bx = 2 * x + dx, by = 2 * y + dy;
            if (bx >= below.width || by >= below.height) continue;
            const std::size_t k = std::size_t(by) * std::size_t(below.width) + std::size_t(bx);
            sum += below.radiance[k] * below.count[k];
          }
        const std::size_t k = std::size_t(y) * std::size_t(at.width) + std::size_t(x);
        at.radiance[k] = at.count[k] > 0 ? sum * (1 / at.count[k]) : Rgb{};
      }
    });
  }
}

// What the march reads of a texel, in one place (one or two cache lines a sample rather than six
// arrays' worth): its plane (the mean normal, not unit, and its offset from the eye), the depth
// range a meeting point is kept in, and the solid's end over the depth; lo = +inf marks a texel
// over misses only.
struct Texel {
  Vec3 n;
  float n2;     // |n|^2
  float plane;  // dot(mean - eye, n)
  float zc;     // the mean's linear depth: the meeting point where a ray runs along the plane
  float lo, hi;
  float grow;
};

// The camera's frame: screen point (x, y) in pixels (row 0 at the top) at linear depth z is
// eye + z (f + X r + Y u), and a screen direction (cos phi, sin phi) is the world direction
// cos phi r - sin phi u.
struct Frame {
  Vec3 eye, f, r, u;
  float width = 1, height = 1, tan_half = 1;
  // The camera ray through screen point (x, y), scaled so that its component along f is 1: the
  // point at linear depth z on it is eye + z ray(x, y).
  Vec3 ray(float x, float y) const {
    const float sx = (2 * x / width - 1) * tan_half * width / height;
    const float sy = (1 - 2 * y / height) * tan_half;
    return f + r * sx + u * sy;
  }
  // The change of ray(x, y) per pixel along screen direction (dx, dy).
  Vec3 ray_step(float dx, float dy) const {
    return r * (2 * dx / width * tan_half * width / height) - u * (2 * dy / height * tan_half);
  }
  Vec3 screen_direction(double phi) const {
    return r * float(std::cos(phi)) - u * float(std::sin(phi));
  }
};

// A cascade's screen direction, the same for each of its probes: its unit step on the screen,
// the camera ray's change per pixel along it (Frame::ray_step) and the direction in the world.
struct ScreenDirection {
  float dx = 0, dy = 0;
  Vec3 g, world;
};

// The spread of a texel's depths, over the nearest, beyond which it spans a depth step (measured:
// 0.1 against 0.05, 0.25 and 0.5).
constexpr float kStep = 0.1f;

// The length of a texel's mean unit normal above which it counts as one surface's.
constexpr float kFlat = 0.95f;

// Each level's texels as the march reads them, from the depth pyramid and the means (the
// position, normal and solid of their hits). A texel of one surface (its normals agree) is its
// plane, met within [zc / 2, 2 zc]; one across an edge is kept within its depth range; one across
// a depth step (a lamp over the floor far behind it) is its nearest surface alone: the plane
// through the mean of both, or the whole range between them, was a phantom slab carrying the
// lamp's light over the step.
std::vector<std::vector<Texel>> make_texels(const DepthPyramid& depth, const Means& m,
                                            const Frame& frame) {
  std::vector<std::vector<Texel>> levels(m.levels.size());
  for (std::size_t l = 0; l < m.levels.size(); ++l) {
    const Means::Level& ml = m.levels[l];
    const DepthPyramid::Level& dl = depth.level(int(l));
    std::vector<Texel>& out = levels[l];
    assign_huge(out, ml.count.size());
    parallel_for(ml.height, [&](int y) {
      for (int x = 0; x < ml.width; ++x) {
        const std::size_t k = std::size_t(y) * std::size_t(ml.width) + std::size_t(x);
        Texel& t = out[k];
        t.n = ml.normal[k];
        t.n2 = dot(t.n, t.n);
        t.plane = dot(ml.position[k] - frame.eye, t.n);
        t.zc = dot(ml.position[k] - frame.eye, frame.f);
        t.grow = ml.grow[k];
        if (!(ml.count[k] > 0)) {  // only misses: the sky occludes nothing
          t.lo = std::numeric_limits<float>::infinity();
          t.hi = -t.lo;
          continue;
        }
        const bool flat = t.n2 > kFlat * kFlat;
        t.lo = flat ? 0.5f * t.zc : dl.lo[k];
        t.hi = flat ? 2 * t.zc : dl.hi[k];
        if (dl.hi[k] > dl.lo[k] * (1 + kStep)) t.lo = t.hi = dl.lo[k];
      }
    });
  }
  return levels;
}

// The unit vector in the slice of screen direction w about the view vector v, perpendicular to
// v and towards w.
Vec3 slice_tangent(Vec3 v, Vec3 w) {
  return normalize(w - v * dot(v, w));
}

// The angle of a point (a along the view vector, b along the slice's tangent) from the view
// vector, in [0, pi]; a point behind the slice's half-plane counts as on its edge. A minimax
// polynomial for atan on [0, 1] (error under 1e-5 radians, a tenth of a thousandth of a
// sector): the march takes four a sample.
inline float slice_angle(float a, float b) {
  b = std::max(b, 0.0f);
  const float ax = std::abs(a);
  const float lo = std::min(ax, b), hi = std::max(ax, b);
  if (!(hi > 0)) return 0;
  const float q = lo / hi, q2 = q * q;
  float t = ((-0.0464964749f * q2 + 0.15931422f) * q2 - 0.327622764f) * q2 * q + q;
  if (b > ax) t = 1.57079632679f - t;
  return a < 0 ? 3.14159265359f - t : t;
}

// Four directions marched together, a lane each (seed 001 section 4.2 marches four rays at once).
using Lanes = std::experimental::fixed_size_simd<float, 4>;

// slice_angle on every lane, with its comparisons as std::min and std::max make them (the same
// bits as the scalar one).
[[gnu::always_inline]] inline Lanes slice_angle(Lanes a, Lanes b) {
  where(b < 0.0f, b) = 0.0f;
  const Lanes ax = std::experimental::abs(a);
  Lanes lo = ax, hi = ax;
  where(b < ax, lo) = b;
  where(ax < b, hi) = b;
  const Lanes q = lo / hi, q2 = q * q;
  Lanes t = ((-0.0464964749f * q2 + 0.15931422f) * q2 - 0.327622764f) * q2 * q + q;
  where(b > ax, t) = 1.57079632679f - t;
  where(a < 0.0f, t) = 3.14159265359f - t;
  where(!(hi > 0.0f), t) = 0.0f;
  return t;
}

// The sectors whose centre angle a solid from angle lo to hi covers (lo <= hi), as bits of a
// mask of n sectors: a sector's radiance stands for its centre's direction, as the final
// gather's weights take it (so that a plane's own horizon splits its sectors where the gather
// does, and a uniform sky over it comes out exact).
inline std::uint32_t sector_bits(float lo, float hi, float sectors_per_radian, int n) {
  const int k1 = std::max(0, int(std::ceil(lo * sectors_per_radian - 0.5f)));
  const int k2 = std::min(n - 1, int(std::floor(hi * sectors_per_radian - 0.5f)));
  if (k1 > k2) return 0;
  const std::uint64_t upto = (std::uint64_t(2) << k2) - 1;
  const std::uint64_t below = (std::uint64_t(1) << k1) - 1;
  return std::uint32_t(upto & ~below);
}

constexpr float kOnPlane2 = kOnPlane * kOnPlane;

// What every cascade of a bounce shares.
struct Shared {
  const SolveContext& ctx;
  const SsrcOptions& o;
  const SpwiOptions& probe_options;
  const Layout& layout;
  const Frame& frame;
  const std::vector<std::vector<Texel>>& texels;
  const Means& means;  // the radiance
  const Background& bg;
  float sectors_per_radian;
  int per_bin;                                // sectors per stored radiance bin
  std::uint32_t all;                          // every sector's bit
  std::vector<float> cos_sector, sin_sector;  // at each sector's centre angle
  // Each sector's share of its bin: its solid angle (sin theta d theta d phi) over the bin's. A
  // plain mean would give a sector by the view vector, a sliver of the sphere, a bin's share of
  // the light: a bright light there (a panel behind the camera, a lamp between the camera and
  // the floor under it) would come out several times too bright.
  std::vector<float> bin_weight;
  // Prefix sums over the sectors before k of cos sin and sin^2 (the gather's cosine weights).
  std::vector<float> cos_sum, sin_sum;
  // Per cascade, its screen directions (worked out once, not per probe).
  std::vector<std::vector<ScreenDirection>> directions;
};

// One direction of a probe being marched: where it runs on the screen, its slice's tangent, the
// sectors occluded so far and the radiance of each sector.
struct Ray {
  // Its samples at screen point (ox + r dx, oy + r dy) for r along the interval: (ox, oy) is the
  // probe and (dx, dy) a unit direction, except for --merge fix's segments to an upper probe.
  float ox = 0, oy = 0;
  float dx = 0, dy = 0;
  Vec3 o;  // the camera ray (Frame::ray) through (ox, oy)
  Vec3 g;  // the change of the camera ray per unit of r along the line
  Vec3 t;
  float horizon = 0;  // the angle of the probe's own tangent plane in the slice
  std::uint32_t occluded = 0;
  bool left = false;  // its march left the screen
  std::array<Rgb, 32> sectors{};
};

// The screen coordinate of the centre of the pixel a probe of tile p (tiles `spacing` pixels
// wide, `size` pixels in all) sits on: the tile's middle pixel, the last one past the edge.
inline float probe_pixel(int p, int spacing, int size) {
  return float(std::min(p * spacing + spacing / 2, size - 1)) + 0.5f;
}

// One cascade, marched and merged with the one above.
struct Cascade {
  const Shared& s;
  int i;
  const std::vector<spwi::Probe>& probes;
  const std::vector<spwi::Probe>& upper_probes;
  const std::vector<Rgb>& upper;
  std::vector<Rgb>& lower;
  // What --offscreen world's rays read at the surfaces they meet besides their emission (null:
  // nothing): the radiance cache holds the light reflected after all bounces but the last, which
  // only the last bounce's rays should see (read by the earlier ones, an enclosure at two
  // bounces came out 1.4% bright).
  const RadianceCache* reflected;

  // Marches up to 4 rays together from the probe at position p, view vector v: the samples of
  // their interval from the pyramid level of its step.
  void march(Ray* rays, int n, Vec3 p, Vec3 v, Vec3 normal) const {
    const Layout& l = s.layout;
    const int level = l.level(i);
    const double step = double(1 << level);
    const double a = l.start(i);
    const bool top = l.top(i);
    const Means::Level& ml = s.means.levels[std::size_t(level)];
    const Texel* texels = s.texels[std::size_t(level)].data();
    const int width = s.ctx.g.width, height = s.ctx.g.height;
    const float stretch = float(step);  // each sample stands for this much of the line
    // The top cascade runs to the screen's edge: at most its diagonal in steps.
    const int most = l.samples(i);
    // The rays' own values, one lane each (lanes past n stay idle).
    Lanes rox = 0, roy = 0, roz = 0, rgx = 0, rgy = 0, rgz = 0, rtx = 0, rty = 0, rtz = 0,
          horizon = 0;
    for (int j = 0; j < n; ++j) {
      rox[j] = rays[j].o.x, roy[j] = rays[j].o.y, roz[j] = rays[j].o.z;
      rgx[j] = rays[j].g.x, rgy[j] = rays[j].g.y, rgz[j] = rays[j].g.z;
      rtx[j] = rays[j].t.x, rty[j] = rays[j].t.y, rtz[j] = rays[j].t.z;
      horizon[j] = rays[j].horizon;
    }
    int active = n;
    for (int m = 0; m < most && active > 0; ++m) {
      const float r = float(a + double(m + 1) * step);
      // Each ray's texel; the lanes whose texel holds hits go on together.
      std::array<std::size_t, 4> at{};
      std::array<bool, 4> hit{};
      Lanes nx = 0, ny = 0, nz = 0, n2 = 0, plane = 0, zc = 0, lo = 0, hi = 0, grow = 1;
      bool any = false;
      for (int j = 0; j < n; ++j) {
        Ray& ray = rays[j];
        if (ray.left) continue;
        const float x = ray.ox + r * ray.dx, y = ray.oy + r * ray.dy;
        if (!(x >= 0 && y >= 0 && x < float(width) && y < float(height))) {
          ray.left = true;
          --active;
          continue;
        }
        const std::size_t k =
            std::size_t(int(y) >> level) * std::size_t(ml.width) + std::size_t(int(x) >> level);
        // The next sample's texel is fetched while this one is worked on: the march waited on
        // its texels' loads (a sixth of its time, measured with perf).
        {
          const float fx = x + float(step) * ray.dx, fy = y + float(step) * ray.dy;
          if (fx >= 0 && fy >= 0 && fx < float(width) && fy < float(height))
            __builtin_prefetch(texels + std::size_t(int(fy) >> level) * std::size_t(ml.width) +
                               std::size_t(int(fx) >> level));
        }
        // The texel (make_texels) met by the camera rays at either end of the sample's stretch
        // of the line; solid for the thickness behind.
        const Texel& tx = texels[k];
        if (!(tx.lo <= tx.hi)) continue;  // only misses: the sky occludes nothing
        at[std::size_t(j)] = k;
        hit[std::size_t(j)] = any = true;
        nx[j] = tx.n.x, ny[j] = tx.n.y, nz[j] = tx.n.z, n2[j] = tx.n2;
        plane[j] = tx.plane, zc[j] = tx.zc, lo[j] = tx.lo, hi[j] = tx.hi, grow[j] = tx.grow;
      }
      if (!any) continue;
      // The angles the texels' solids cover, all lanes at once: the scalar expressions'
      // operations in their order, so that the bits do not depend on how many rays go together.
      Lanes t0 = float(kPi), t1 = 0;
      for (float e : {-0.5f, 0.5f}) {
        const float re = r + e * stretch;
        const Lanes gx = rox + rgx * re, gy = roy + rgy * re, gz = roz + rgz * re;
        const Lanes den = gx * nx + gy * ny + gz * nz;
        Lanes z = zc;
        where(den * den > kParallel * (gx * gx + gy * gy + gz * gz) * n2, z) = plane / den;
        where(z < lo, z) = lo;
        where(hi < z, z) = hi;
        for (int side = 0; side < 2; ++side) {
          const Lanes depth = side == 0 ? z : z * grow;
          const Lanes dx = (s.frame.eye.x + gx * depth) - p.x;
          const Lanes dy = (s.frame.eye.y + gy * depth) - p.y;
          const Lanes dz = (s.frame.eye.z + gz * depth) - p.z;
          Lanes t = slice_angle(dx * v.x + dy * v.y + dz * v.z, dx * rtx + dy * rty + dz * rtz);
          // A point on or under the probe's tangent plane (within about a degree: a plane's
          // own pixels, a convex surface's neighbours) lies below its horizon, where its
          // angle as projected on the slice might not.
          const Lanes h = dx * normal.x + dy * normal.y + dz * normal.z;
          const auto under = h <= 0.0f || h * h <= kOnPlane2 * (dx * dx + dy * dy + dz * dz);
          where(under && t < horizon, t) = horizon;
          where(t < t0, t0) = t;
          where(t1 < t, t1) = t;
        }
      }
      for (int j = 0; j < n; ++j) {
        if (!hit[std::size_t(j)]) continue;
        Ray& ray = rays[j];
        const std::uint32_t bits = sector_bits(t0[j], t1[j], s.sectors_per_radian, l.sectors);
        std::uint32_t first = bits & ~ray.occluded;
        if (!first) continue;
        ray.occluded |= bits;
        const Rgb& radiance = ml.radiance[at[std::size_t(j)]];
        for (; first; first &= first - 1)
          ray.sectors[std::size_t(std::countr_zero(first))] += radiance;
      }
    }
    if (top)
      for (int j = 0; j < n; ++j) rays[j].left = true;
  }

  // How many sectors lie before a horizon's angle: those above the probe's surface.
  int above_horizon(float horizon) const {
    return std::clamp(int(std::ceil(horizon * s.sectors_per_radian - 0.5f)), 0, s.layout.sectors);
  }

  // --offscreen world: each open sector of a ray that left the screen takes what an exact ray
  // from the probe along its centre's direction meets, as SPWI's rays do: the emission, with
  // later bounces the radiance cache's reflected light, or the sky. It starts at the probe: from
  // the point of the sector's line seen where the line left the screen, or at the interval's
  // start, a ray that had passed behind an on-screen wall (through its thin solid between two
  // samples) starts outside the room and sees the sky through the wall (rooms lit through a
  // window 1.3-1.5 relative RMSE against 0.15, an emitting enclosure 1% dark). The price: what
  // the cascades below saw on screen, an upper probe's ray meets again at other angles (a lamp
  // in view counted twice near it; docs/QUALITY.md).
  void world(Ray& ray, Vec3 p, Vec3 v, Vec3 normal, std::uint64_t& traced) const {
    // Only the sectors above the probe's surface: extend_over_horizon overwrites the others.
    const int above = above_horizon(ray.horizon);
    for (int k = 0; k < above; ++k) {
      if (ray.occluded >> k & 1u) continue;
      const Vec3 d = v * s.cos_sector[std::size_t(k)] + ray.t * s.sin_sector[std::size_t(k)];
      const spaceland::Ray r{s.ctx.rays.spawn(p, normal, d), d};
      ++traced;
      Hit h;
      Rgb l;
      if (!s.ctx.rays.intersect(r, h)) {
        l = s.bg.sky(d);
      } else {
        l = emission_at(s.ctx.scene, h);
        if (reflected)
          l += reflected->reflected(h.position, dot(h.geometric_normal, d) < 0
                                                    ? h.geometric_normal
                                                    : -h.geometric_normal);
      }
      ray.sectors[std::size_t(k)] += l;
    }
  }

  // The open sectors of a ray that left the screen see the sky.
  void sky(Ray& ray, Vec3 v) const {
    const int n = s.layout.sectors;
    for (int k = 0; k < n; ++k) {
      if (ray.occluded >> k & 1u) continue;
      const Vec3 d = v * s.cos_sector[std::size_t(k)] + ray.t * s.sin_sector[std::size_t(k)];
      ray.sectors[std::size_t(k)] += s.bg.sky(d);
    }
  }

  // The open sectors of a ray take the upper probes' radiance in its direction: per sector, the
  // mean of its two children's (flatland's merge, sector by sector), each read in its bin.
  void merge(Ray& ray, int dir, const cascade::Corners& c) const {
    const std::size_t bins = std::size_t(s.layout.bins), per_bin = std::size_t(s.per_bin);
    const int up_dirs = s.layout.directions(i + 1);
    const std::uint32_t open = ~ray.occluded & s.all;
    if (!open) return;
    for (int q = 0; q < c.n; ++q) {
      const float w = 0.5f * c.w[std::size_t(q)];
      if (!(w > 0)) continue;
      const Rgb* a = upper.data() + (std::size_t(c.index[std::size_t(q)]) * std::size_t(up_dirs) +
                                     std::size_t(2 * dir)) *
                                        bins;
      const Rgb* b = a + bins;
      for (std::uint32_t bits = open; bits; bits &= bits - 1) {
        const std::size_t k = std::size_t(std::countr_zero(bits));
        ray.sectors[k] += (a[k / per_bin] + b[k / per_bin]) * w;
      }
    }
  }

  // A ray's sectors below its probe's surface hold that surface's own light (its samples occlude
  // there) or the sky under it, which no direction above the surface sees; they take the value
  // of the last sector above it (those above are the ones before the horizon's angle: the cosine
  // nv cos(theta) + nt sin(theta) changes sign once on [0, pi]). The rays below, whose
  // directions all lie above their own surfaces, merge with these: on a plane the horizon's angle
  // changes across a direction's wedge and from probe to probe (their view vectors differ), and
  // the sectors as traced would darken every sector near it.
  void extend_over_horizon(Ray& ray) const {
    const int above = above_horizon(ray.horizon);
    if (above == 0) return;
    for (int k = above; k < s.layout.sectors; ++k)
      ray.sectors[std::size_t(k)] = ray.sectors[std::size_t(above - 1)];
  }

  void probe(int px, int py, std::uint64_t& traced) const {
    const Layout& l = s.layout;
    const std::uint64_t q =
        std::uint64_t(py) * std::uint64_t(l.tiles.nx[std::size_t(i)]) + std::uint64_t(px);
    const spwi::Probe& pr = probes[std::size_t(q)];
    if (!pr.valid) return;
    const int spacing = l.tiles.spacing(i);
    const float cx = probe_pixel(px, spacing, s.ctx.g.width);
    const float cy = probe_pixel(py, spacing, s.ctx.g.height);
    const Vec3 v = normalize(s.frame.eye - pr.p);
    cascade::Corners c;
    const bool merges =
        !l.top(i) &&
        spwi::upper_corners(l.tiles, i + 1, spwi::tile_centre(px, spacing),
                            spwi::tile_centre(py, spacing), pr, upper_probes, s.probe_options, c);
    const int dirs = l.directions(i);
    Rgb* out = lower.data() + std::size_t(q) * std::size_t(dirs) * std::size_t(l.bins);
    const Vec3 g0 = s.frame.ray(cx, cy);
    std::array<Ray, 4> rays;
    // Stored per bin: the mean of its sectors over their solid angles.
    const auto store = [&](Ray& ray, int d) {
      extend_over_horizon(ray);
      Rgb* bins = out + std::size_t(d) * std::size_t(l.bins);
      for (int b = 0; b < l.bins; ++b) {
        Rgb sum{};
        for (int k = b * s.per_bin; k < (b + 1) * s.per_bin; ++k)
          sum += ray.sectors[std::size_t(k)] * s.bin_weight[std::size_t(k)];
        bins[b] = sum;
      }
    };
    const auto start = [&](Ray& ray, int d) {
      const ScreenDirection& sd = s.directions[std::size_t(i)][std::size_t(d)];
      ray = Ray{};
      ray.ox = cx, ray.oy = cy;
      ray.dx = sd.dx, ray.dy = sd.dy;
      ray.o = g0;
      ray.g = sd.g;
      ray.t = slice_tangent(v, sd.world);
      ray.horizon = slice_angle(-dot(pr.n, ray.t), dot(pr.n, v));
    };
    if (merges && s.o.merge == SpwiMerge::fix) {
      for (int d = 0; d < dirs; ++d) fixed(rays, d, c, cx, cy, pr, v, store, start, traced);
      return;
    }
    for (int first = 0; first < dirs; first += l.rays) {
      const int n = std::min(l.rays, dirs - first);
      for (int j = 0; j < n; ++j) start(rays[std::size_t(j)], first + j);
      march(rays.data(), n, pr.p, v, pr.n);
      for (int j = 0; j < n; ++j) {
        Ray& ray = rays[std::size_t(j)];
        // A ray with no upper probe to go on with (all on the sky or facing away) is as one
        // that left the screen.
        if (ray.left || !merges)
          off_screen(ray, pr, v, traced);
        else
          merge(ray, first + j, c);
        store(ray, first + j);
      }
    }
  }

  // What a ray that left the screen sees in its open sectors.
  void off_screen(Ray& ray, const spwi::Probe& pr, Vec3 v, std::uint64_t& traced) const {
    if (s.o.offscreen == SsrcOffscreen::world)
      world(ray, pr.p, v, pr.n, traced);
    else
      sky(ray, v);
  }

  // --merge fix (flatland's bilinear fix, seed 002): direction d marched once per upper probe,
  // a lane each, along the segment from where this cascade's interval starts to where that
  // probe's starts, and merged with that probe alone; the segments' results weighted as the
  // merge weighs the probes. The sectors stay those of the direction's own slice, as the fix in
  // flatland keeps the direction's label. Four times the march of a merged cascade.
  template <class Store, class Start>
  void fixed(std::array<Ray, 4>& rays, int d, const cascade::Corners& c, float cx, float cy,
             const spwi::Probe& pr, Vec3 v, const Store& store, const Start& start,
             std::uint64_t& traced) const {
    const Layout& l = s.layout;
    const int up_spacing = l.tiles.spacing(i + 1);
    const int up_nx = l.tiles.nx[std::size_t(i + 1)];
    const float a = float(l.start(i)), b = float(l.end(i));
    Ray sum;
    start(sum, d);
    float weight = 0;
    // The upper probes the merge weighs.
    std::array<std::uint64_t, 8> index{};
    std::array<float, 8> w{};
    int count = 0;
    for (int q = 0; q < c.n; ++q)
      if (c.w[std::size_t(q)] > 0) {
        index[std::size_t(count)] = c.index[std::size_t(q)];
        w[std::size_t(count++)] = c.w[std::size_t(q)];
      }
    for (int first = 0; first < count; first += 4) {
      const int n = std::min(4, count - first);
      for (int j = 0; j < n; ++j) {
        Ray& ray = rays[std::size_t(j)];
        start(ray, d);
        // The upper probe's pixel centre; the line through the samples
        // (ox, oy) + r (dx, dy) meets this cascade's start at r = a and the upper probe's at b.
        const std::uint64_t uq = index[std::size_t(first + j)];
        const float ux = probe_pixel(int(uq % std::uint64_t(up_nx)), up_spacing, s.ctx.g.width);
        const float uy = probe_pixel(int(uq / std::uint64_t(up_nx)), up_spacing, s.ctx.g.height);
        const float ddx = (ux - cx) / (b - a), ddy = (uy - cy) / (b - a);
        ray.dx += ddx, ray.dy += ddy;
        ray.ox = cx - a * ddx, ray.oy = cy - a * ddy;
        ray.o = s.frame.ray(ray.ox, ray.oy);
        ray.g = s.frame.ray_step(ray.dx, ray.dy);
      }
      march(rays.data(), n, pr.p, v, pr.n);
      for (int j = 0; j < n; ++j) {
        Ray& ray = rays[std::size_t(j)];
        const float wj = w[std::size_t(first + j)];
        if (ray.left) {
          off_screen(ray, pr, v, traced);
        } else {
          cascade::Corners one;
          one.n = 1;
          one.index[0] = index[std::size_t(first + j)];
          one.w[0] = 1;
          merge(ray, d, one);
        }
        for (int k = 0; k < l.sectors; ++k)
          sum.sectors[std::size_t(k)] += ray.sectors[std::size_t(k)] * wj;
        weight += wj;
      }
    }
    if (weight > 0)
      for (int k = 0; k < l.sectors; ++k) sum.sectors[std::size_t(k)] *= 1 / weight;
    store(sum, d);
  }

  // Marches and merges every probe; returns the rays traced off screen.
  std::uint64_t run() const {
    const int nx = s.layout.tiles.nx[std::size_t(i)];
    std::atomic<std::uint64_t> count{0};
    parallel_for(s.layout.tiles.ny[std::size_t(i)], [&](int py) {
      std::uint64_t traced = 0;
      for (int px = 0; px < nx; ++px) probe(px, py, traced);
      count.fetch_add(traced, std::memory_order_relaxed);
    });
    return count.load();
  }
};

// The final gather: per pixel, the weight of each cascade-0 direction's sectors for its normal
// (the cosine over each sector's solid angle, at the direction's own screen angle, where its
// probes' horizons split the sectors), then the depth- and normal-weighted cascade-0 probes
// around it; the cosine-weighted mean radiance over the pixel's hemisphere (false: no probe).
struct Gather {
  const Shared& s;
  const std::vector<spwi::Probe>& probes;
  const std::vector<Rgb>& store;
  std::vector<Vec3> screen;  // each cascade-0 direction in the world
  // Glossy scenes: kCellPoints screen directions spread evenly over each cascade-0 direction's
  // angle, d-major (lobe_weights).
  std::vector<Vec3> screen_points;
  // --gather probe: each probe's mean about its own normal and view vector, once (false where
  // it has none: a probe on the sky, or facing away).
  std::vector<Rgb> probe_mean;
  std::vector<std::uint8_t> probe_has;

  // The weights of each direction's bins for a surface of normal n seen along v, into w
  // (q0 x bins); their sum.
  float weights(Vec3 v, Vec3 n, float* w) const {
    const Layout& l = s.layout;
    const float nv = dot(n, v);
    const int sectors = l.sectors, bins = l.bins;
    float total = 0;
    for (int d = 0; d < l.q0; ++d) {
      // cos(w, n) = nv cos(theta) + nt sin(theta) is positive below the surface's horizon angle
      // theta_h: the sectors whose centres lie before it, summed per bin from prefix sums.
      const float nt = dot(n, slice_tangent(v, screen[std::size_t(d)]));
      const int above = std::clamp(
          int(std::ceil(slice_angle(-nt, nv) * s.sectors_per_radian - 0.5f)), 0, sectors);
      float* wd = w + std::size_t(d * bins);
      for (int b = 0; b < bins; ++b) {
        wd[b] = 0;
        if (b * s.per_bin >= above) continue;
        const std::size_t from = std::size_t(b * s.per_bin);
        const std::size_t to = std::size_t(std::min((b + 1) * s.per_bin, above));
        wd[b] = std::max(
            0.0f, nv * (s.cos_sum[to] - s.cos_sum[from]) + nt * (s.sin_sum[to] - s.sin_sum[from]));
        total += wd[b];
      }
    }
    return total;
  }

  // A glossy surface's specular lobe (GGX width alpha about the shading normal n, seen along v,
  // towards the viewer) over each direction's bins, into w (q0 x bins): the lobe's weight
  // (lobe_weight) at each sector's centre angle of each point's slice, times the sector's solid
  // angle (sin theta), the lobe taken no narrower than a bin (about 4 pi / (q0 bins)); their sum.
  // Seed 001 2.6's widest query reads merged cascade 0 with it.
  float lobe_weights(Vec3 v, Vec3 n, float alpha, float* w) const {
    const Layout& l = s.layout;
    const float cell = cap_alpha(4 * kPi / (double(l.q0) * l.bins)), a = std::max(alpha, cell);
    const bool fine = cell > alpha / cascade::kLobeCells;
    // A bin wider than a quarter of the lobe: cascade::kCellPoints screen angles (and its 4
    // sectors at 32).
    const int points = fine ? cascade::kCellPoints : 1;
    // Directions further than 5 lobe widths from the mirror direction r (the half vector 5
    // alpha off the normal) are left out, whole slices at once: at roughness 0.3 the weights
    // take a third of the time (a metal floor under a gradient sky, 400 x 300: 1.65 s to 0.6 s;
    // 3 widths, 0.5 s, took its error from 4.9% to 6.3%, the lobe's peak leaving the mirror
    // direction at grazing views).
    const Vec3 r = reflect(v, n);
    const float reach = std::min(float(kPi), 2 * std::atan(5 * a));
    const float cos_reach = std::cos(reach);
    float total = 0;
    for (int d = 0; d < l.q0; ++d) {
      float* wd = w + std::size_t(d * l.bins);
      std::fill(wd, wd + l.bins, 0.0f);
      for (int j = 0; j < points; ++j) {
        const Vec3 t =
            slice_tangent(v, fine ? screen_points[std::size_t(d * cascade::kCellPoints + j)]
                                  : screen[std::size_t(d)]);
        // The cosine of r's angle to the slice's half-plane (its nearest point: r's projection
        // on the plane, or the view axis where r lies behind it).
        const float rv = dot(r, v), rt = dot(r, t);
        if ((rt > 0 ? std::sqrt(rv * rv + rt * rt) : std::abs(rv)) < cos_reach) continue;
        for (int k = 0; k < l.sectors; ++k) {
          const float sn = s.sin_sector[std::size_t(k)];
          const Vec3 wi = v * s.cos_sector[std::size_t(k)] + t * sn;
          if (dot(wi, r) < cos_reach) continue;
          wd[k / s.per_bin] += lobe_weight(a, n, v, wi) * sn;
        }
      }
      for (int b = 0; b < l.bins; ++b) total += wd[b];
    }
    return total;
  }

  // Probe q's cosine-weighted mean radiance for weights w (summing to total).
  Rgb mean_of(std::uint64_t q, const float* w, float total) const {
    const std::size_t values = std::size_t(s.layout.q0 * s.layout.bins);
    const Rgb* p = store.data() + std::size_t(q) * values;
    Rgb e{};
    for (std::size_t d = 0; d < values; ++d) e += p[d] * w[d];
    return e * (1 / total);
  }

  void prepare_probes() {
    if (s.o.gather != SpwiGather::probe) return;
    probe_mean.assign(probes.size(), Rgb{});
    probe_has.assign(probes.size(), 0);
    parallel_for(int(probes.size()), [&](int q) {
      const spwi::Probe& pr = probes[std::size_t(q)];
      if (!pr.valid) return;
      std::array<float, kMaxDirections * kMaxBins> w;
      const float total = weights(normalize(s.frame.eye - pr.p), pr.n, w.data());
      if (!(total > 0)) return;
      probe_mean[std::size_t(q)] = mean_of(std::uint64_t(q), w.data(), total);
      probe_has[std::size_t(q)] = 1;
    });
  }

  bool operator()(int x, int y, std::size_t k, const Hit& h, Rgb& mean) const {
    cascade::Corners c;
    if (!spwi::gather_corners(s.layout.tiles, 0, x, y, s.ctx.g.linear_depth(k), h.geometric_normal,
                              probes, s.probe_options, c))
      return false;
    Rgb sum{};
    float used = 0;
    if (!probe_mean.empty()) {
      for (int j = 0; j < c.n; ++j) {
        const float cw = c.w[std::size_t(j)];
        const std::size_t q = std::size_t(c.index[std::size_t(j)]);
        if (!(cw > 0) || !probe_has[q]) continue;
        sum += probe_mean[q] * cw;
        used += cw;
      }
    } else {
      std::array<float, kMaxDirections * kMaxBins> w;
      const float total = weights(-s.ctx.g.directions[k], h.shading_normal, w.data());
      return total > 0 && blend(c, w.data(), total, mean);
    }
    if (!(used > 0)) return false;
    mean = sum * (1 / used);
    return true;
  }

  // A glossy pixel's specular lobe (lobe_weights) over the same probes; false where it has none.
  bool lobe(int x, int y, std::size_t k, const Hit& h, float alpha, Rgb& mean) const {
    cascade::Corners c;
    if (!spwi::gather_corners(s.layout.tiles, 0, x, y, s.ctx.g.linear_depth(k), h.geometric_normal,
                              probes, s.probe_options, c))
      return false;
    std::array<float, kMaxDirections * kMaxBins> w;
    const float total =
        lobe_weights(normalize(-s.ctx.g.directions[k]), h.shading_normal, alpha, w.data());
    return total > 0 && blend(c, w.data(), total, mean);
  }

  // The corner probes' means for weights w (summing to total), blended by their gather weights;
  // false where none counts.
  bool blend(const cascade::Corners& c, const float* w, float total, Rgb& mean) const {
    Rgb sum{};
    float used = 0;
    for (int j = 0; j < c.n; ++j) {
      const float cw = c.w[std::size_t(j)];
      if (!(cw > 0)) continue;
      sum += mean_of(c.index[std::size_t(j)], w, total) * cw;
      used += cw;
    }
    if (!(used > 0)) return false;
    mean = sum * (1 / used);
    return true;
  }
};

// Calls visit(k, rays) for every pixel k that sees a surface, rows in parallel; the rays each
// call counts are added to `traced`.
template <class Visit>
void for_each_hit(const GBuffer& g, std::uint64_t& traced, Visit&& visit) {
  std::atomic<std::uint64_t> count{0};
  parallel_for(g.height, [&](int y) {
    std::uint64_t local = 0;
    for (int x = 0; x < g.width; ++x) {
      const std::size_t k = std::size_t(y) * std::size_t(g.width) + std::size_t(x);
      if (g.found[k]) visit(k, local);
    }
    count.fetch_add(local, std::memory_order_relaxed);
  });
  traced += count.load();
}

}  // namespace

Layout make_layout(int width, int height, const SsrcOptions& o) {
  Layout l;
  SpwiOptions so;
  so.probe_spacing = o.probe_spacing;
  l.tiles.width = width;
  l.tiles.height = height;
  l.tiles.levels.spacing0 = spwi::probe_spacing_for(so, width, height);
  l.tiles.levels.spacing_step = 1;
  l.q0 = o.directions;
  l.r0 = o.interval > 0 ? o.interval : 4 * l.tiles.levels.spacing0;
  l.steps = o.steps;
  l.sectors = o.sectors;
  l.bins = std::min(kMaxBins, o.sectors);
  l.rays = o.rays;
  int count = o.cascades;
  if (count == 0) {
    const double diagonal = std::sqrt(double(width) * width + double(height) * height);
    count = cascade::count_until(cascade::kMaxCascades,
                                 [&](int i) { return double(l.r0) * double(1u << i) < diagonal; });
  }
  l.tiles.levels.count = count;
  for (int i = 0; i < count; ++i) {
    const int s = l.tiles.spacing(i);
    l.tiles.nx.push_back((width + s - 1) / s);
    l.tiles.ny.push_back((height + s - 1) / s);
  }
  return l;
}

std::uint64_t Layout::bytes() const {
  std::uint64_t largest = 0, probe_bytes = 0;
  for (int i = 0; i < count(); ++i) {
    largest = std::max(largest, values(i));
    probe_bytes += probes(i) * sizeof(spwi::Probe);
  }
  const std::uint64_t pixels = std::uint64_t(tiles.width) * std::uint64_t(tiles.height);
  const std::uint64_t pyramid = DepthPyramid::bytes(tiles.width, tiles.height);
  // The depth pyramid (2 floats a texel), the means and the march's texels over the same texels,
  // all three at once while the texels are made; per pixel the direct light, the albedo, the
  // samples' radiance and a bounce's image, and the solid's end.
  // A glossy scene's pixels also keep their specular albedo and lobe width, and what a later
  // bounce marches: their light with the share of a uniform light they reflect, and its image.
  return 2 * largest * sizeof(Rgb) + probe_bytes + pyramid +
         pyramid / (2 * sizeof(float)) * (Means::bytes_per_texel() + sizeof(Texel)) +
         4 * pixels * sizeof(Rgb) + pixels * sizeof(float) +
         (glossy ? pixels * (4 * sizeof(Rgb) + sizeof(float)) : 0);
}

Status check_options(const SsrcOptions& o) {
  if (o.probe_spacing < 0 || o.probe_spacing > 64)
    return Error{"`ssrc.probe_spacing`: expected 1..64 pixels (0: derived), found " +
                 std::to_string(o.probe_spacing)};
  if (!power_of_two(o.directions) || o.directions > kMaxDirections)
    return Error{"`ssrc.directions`: expected a power of two from 1 to " +
                 std::to_string(kMaxDirections) + ", found " + std::to_string(o.directions)};
  if (o.interval < 0 || o.interval > 4096)
    return Error{"`ssrc.interval`: expected 1..4096 pixels (0: derived), found " +
                 std::to_string(o.interval)};
  if (o.cascades < 0 || o.cascades > cascade::kMaxCascades)
    return Error{"`ssrc.cascades`: expected 0.." + std::to_string(cascade::kMaxCascades) +
                 " (0: derived), found " + std::to_string(o.cascades)};
  if (o.steps < 1 || o.steps > 256)
    return Error{"`ssrc.steps`: expected 1..256 samples an interval, found " +
                 std::to_string(o.steps)};
  if (o.sectors != 8 && o.sectors != 16 && o.sectors != 32)
    return Error{"`ssrc.sectors`: expected 8, 16 or 32 sectors per direction, found " +
                 std::to_string(o.sectors)};
  if (o.rays != 1 && o.rays != 2 && o.rays != 4)
    return Error{"`ssrc.rays`: expected 1, 2 or 4 directions marched together, found " +
                 std::to_string(o.rays)};
  if (!(o.thickness >= 0) || !std::isfinite(o.thickness))
    return Error{"`ssrc.thickness`: expected a fraction of the depth >= 0, found " +
                 io::format_number(o.thickness)};
  if (o.merge != SpwiMerge::bilinear && o.merge != SpwiMerge::bilateral &&
      o.merge != SpwiMerge::bilinear3d && o.merge != SpwiMerge::fix)
    return Error{"`ssrc.merge`: expected bilinear, bilateral, bilinear3d or fix, found " +
                 std::string(to_string(o.merge))};
  if (!(o.merge_edge >= 0) || !(o.gather_edge >= 0) || !std::isfinite(o.merge_edge) ||
      !std::isfinite(o.gather_edge))
    return Error{"`ssrc.merge_edge` and `ssrc.gather_edge`: expected numbers >= 0"};
  if (o.gather != SpwiGather::pixel && o.gather != SpwiGather::probe)
    return Error{"`ssrc.gather`: expected pixel or probe"};
  if (o.offscreen != SsrcOffscreen::sky && o.offscreen != SsrcOffscreen::world)
    return Error{"`ssrc.offscreen`: expected sky or world"};
  if (!(o.gather_normal >= 0 && o.gather_normal <= 64))
    return Error{"`ssrc.gather_normal`: expected an exponent in [0, 64], found " +
                 io::format_number(o.gather_normal)};
  if (o.specular != SpecularQuery::wide)
    return Error{std::string("`ssrc.specular`: expected wide (the widest query, over merged "
                             "cascade 0), found ") +
                 to_string(o.specular) + ": the cone query over ssrc's own intervals is not built"};
  return {};
}

Status check_scene(const Scene& scene) {
  return refuse_fog(scene, "ssrc", "--method pt or grid");
}

Expected<ImageRgb> render(const SolveContext& ctx, const SsrcOptions& o, const Layout& layout,
                          SolveReport& report, Port port) {
  // Glossy pixels add the specular lobe from merged cascade 0 (Gather::lobe); the GPU's kernels
  // shade Lambertian pixels only.
  const bool glossy = layout.glossy;
  if (glossy && port)
    return Error{
        "`device` gpu: ssrc's glossy materials (their specular lobe) are on the CPU "
        "only; use `device` cpu"};
  const std::uint64_t need = layout.bytes();
  report.memory_bytes += need;
  if (need > ctx.max_memory)
    return Error{"ssrc's cascades need about " + io::format_mib(need) +
                 ", more than the `max_memory` limit of " + io::format_mib(ctx.max_memory)};
  const GBuffer& g = ctx.g;
  const std::size_t pixels = std::size_t(g.width) * std::size_t(g.height);
  const CameraRays camera(ctx.scene.camera);
  const Frame frame{camera.origin(),
                    camera.forward(),
                    camera.right(),
                    camera.up(),
                    float(g.width),
                    float(g.height),
                    float(camera.tan_half_fov())};
  const Background bg(ctx.scene);

  // Per pixel, where the solid behind its hit ends (over its depth): where its camera ray leaves
  // the object it entered (the next hit on the same object: a sphere's, a box's far side), else
  // `thickness` behind (a sheet with nothing of its own behind it: a floor, a wall's face).
  Stopwatch watch;
  std::vector<float> grow;
  assign_huge(grow, pixels, 1 + o.thickness);
  if (o.backfaces) {
    for_each_hit(g, report.rays, [&](std::size_t k, std::uint64_t& rays) {
      const Hit& h = g.hits[k];
      const Vec3 d = g.directions[k];
      Hit exit;
      ++rays;
      if (!ctx.rays.intersect(spaceland::Ray{ctx.rays.spawn(h.position, h.geometric_normal, d), d},
                              exit) ||
          exit.object != h.object)
        return;
      const float z = g.linear_depth(k), back = dot(exit.position - frame.eye, frame.f);
      if (z > 0 && back > z) grow[k] = back / z;
    });
    report.stages.push_back({"back faces", watch.ms()});
  }
  watch = Stopwatch();
  std::vector<std::vector<Texel>> texels;
  Means means;
  {
    const DepthPyramid depth = DepthPyramid::build(g);
    means = make_means(g, depth, grow);
    texels = make_texels(depth, means, frame);
    // What the texels hold is not needed again: the radiance and counts stay, per bounce.
    for (Means::Level& ml : means.levels) {
      ml.position = {};
      ml.normal = {};
      ml.grow = {};
    }
  }
  report.stages.push_back({"pyramid", watch.ms()});

  // Per pixel: the emission and the sun's light reflected there (exact shadow rays), the light
  // every bounce's image starts from.
  watch = Stopwatch();
  std::vector<Rgb> direct, albedo, radiance;
  for (std::vector<Rgb>* v : {&direct, &albedo, &radiance}) assign_huge(*v, pixels);
  // Glossy scenes, per pixel: the specular lobe's albedo (F0 A + B; zero on a Lambertian) and
  // width (-1 on a Lambertian), and what a later bounce marches: the emission and the sun's light
  // with the share of a uniform light the surface reflects (hemispherical_albedo, as the grid's
  // voxels), the camera's view-dependent highlight left out; `next` the light it reflects so.
  std::vector<Rgb> specular, bounce_albedo, bounce_direct, next;
  std::vector<float> alpha;
  if (glossy) {
    for (std::vector<Rgb>* v : {&specular, &bounce_albedo, &bounce_direct, &next})
      assign_huge(*v, pixels);
    assign_huge(alpha, pixels, -1.0f);  // -1: Lambertian
  }
  {
    const SunLight sun(ctx.scene, ctx.rays, ctx.sun_rays);
    for_each_hit(g, report.rays, [&](std::size_t k, std::uint64_t& rays) {
      const Hit& h = g.hits[k];
      direct[k] = radiance[k] = emission_at(ctx.scene, h);
      const Brdf brdf = glossy ? brdf_at(ctx.scene, h) : Brdf{};
      if (!glossy || brdf.lambertian) {
        albedo[k] = albedo_at(ctx.scene, h);
        if (sun.on()) direct[k] += sun.reflected(h, albedo[k], rays);
        if (glossy) {
          bounce_albedo[k] = albedo[k];
          bounce_direct[k] = direct[k];
        }
        return;
      }
      const Vec3 wo = normalize(-g.directions[k]);
      const LobeAlbedo lobes = lobe_albedo(brdf, std::max(dot(h.shading_normal, wo), 0.0f));
      albedo[k] = lobes.diffuse;
      specular[k] = lobes.specular;
      alpha[k] = brdf.alpha;
      bounce_albedo[k] = hemispherical_albedo(brdf);
      bounce_direct[k] = direct[k];
      if (sun.on()) {
        // One set of shadow rays for both: the BRDF towards the sun's centre for the camera
        // (SunLight::reflected's glossy form), the hemispherical albedo for a later bounce.
        const Rgb white = sun.reflected(h, Rgb{1, 1, 1}, rays);
        direct[k] += sun.glossy(h, brdf, wo, white);
        bounce_direct[k] += bounce_albedo[k] * white;
      }
    });
  }
  report.stages.push_back({"sun", watch.ms()});
  if (ctx.want_exact) report.exact = {direct, albedo};

  SpwiOptions probe_options;
  probe_options.merge = o.merge;
  probe_options.merge_edge = o.merge_edge;
  probe_options.gather_edge = o.gather_edge;
  probe_options.gather_normal = o.gather_normal;
  probe_options.depth_bias = 1;

  Shared s{ctx, o, probe_options, layout, frame, texels, means, bg, 0, 0, 0, {}, {}, {}, {},
           {},  {}};
  for (int i = 0; i < layout.count(); ++i) {
    std::vector<ScreenDirection>& dirs = s.directions.emplace_back();
    for (int d = 0; d < layout.directions(i); ++d) {
      const double phi = layout.phi(i, d);
      ScreenDirection sd;
      sd.dx = float(std::cos(phi));
      sd.dy = float(std::sin(phi));
      sd.g = frame.ray_step(sd.dx, sd.dy);
      sd.world = frame.screen_direction(phi);
      dirs.push_back(sd);
    }
  }
  s.per_bin = layout.sectors / layout.bins;
  s.sectors_per_radian = float(layout.sectors / kPi);
  s.all = std::uint32_t((std::uint64_t(1) << layout.sectors) - 1);
  for (int k = 0; k < layout.sectors; ++k) {
    const double theta = (k + 0.5) * kPi / layout.sectors;
    s.cos_sector.push_back(float(std::cos(theta)));
    s.sin_sector.push_back(float(std::sin(theta)));
  }
  for (int b = 0; b < layout.bins; ++b) {
    float sum = 0;
    for (int k = b * s.per_bin; k < (b + 1) * s.per_bin; ++k) sum += s.sin_sector[std::size_t(k)];
    for (int k = b * s.per_bin; k < (b + 1) * s.per_bin; ++k)
      s.bin_weight.push_back(s.sin_sector[std::size_t(k)] / sum);
  }
  s.cos_sum.push_back(0);
  s.sin_sum.push_back(0);
  for (int k = 0; k < layout.sectors; ++k) {
    s.cos_sum.push_back(s.cos_sum.back() +
                        s.cos_sector[std::size_t(k)] * s.sin_sector[std::size_t(k)]);
    s.sin_sum.push_back(s.sin_sum.back() +
                        s.sin_sector[std::size_t(k)] * s.sin_sector[std::size_t(k)]);
  }

  // The first bounce marches the emission alone: the sun's light a sample reflects is a second
  // bounce (the path tracer's `--bounces 1` has one diffuse reflection, at the camera's hit),
  // which the next bounce's march of the first image carries.
  ImageRgb img;
  // Every cascade's probes, placed once for all bounces (Layout::bytes counts them all).
  std::vector<std::vector<spwi::Probe>> probes(std::size_t(layout.count()));
  for (int i = 0; i < layout.count(); ++i)
    probes[std::size_t(i)] = spwi::place_probes(ctx.scene, g, layout.tiles, i, probe_options);
  if (port) {
    static_assert(sizeof(Texel) == kTexelFloats * sizeof(float));
    Prepared p{layout,       frame.eye,    frame.f,      frame.r,   frame.u,  frame.tan_half,
               {},           radiance,     direct,       albedo,    probes,   probe_options,
               s.cos_sector, s.sin_sector, s.bin_weight, s.cos_sum, s.sin_sum};
    for (std::size_t l = 0; l < means.levels.size(); ++l)
      p.levels.push_back({means.levels[l].width, means.levels[l].height,
                          std::as_bytes(std::span<const Texel>(texels[l])), means.levels[l].count});
    return port(ctx, o, p, report);
  }
  const std::vector<spwi::Probe> none;
  // Two stores, kept from cascade to cascade and bounce to bounce: a fresh 200 MB store a cascade
  // (cascade 0 at 1920x1080) cost more in page faults than its march.
  std::vector<Rgb> upper, lower;
  reserve_huge(lower, std::size_t(layout.values(0)));
  if (layout.count() > 1) reserve_huge(upper, std::size_t(layout.values(1)));
  for (int bounce = 1; bounce <= ctx.bounces; ++bounce) {
    const std::string of = ctx.bounces > 1 ? " (bounce " + std::to_string(bounce) + ")" : "";
    fill_radiance(means, radiance);
    // One swap a cascade: cascade 0's store is the one `lower` is now when the cascades above
    // it are even in number; it takes the larger.
    if ((upper.capacity() > lower.capacity()) == ((layout.count() - 1) % 2 == 0))
      std::swap(upper, lower);
    for (int i = layout.count() - 1; i >= 0; --i) {
      watch = Stopwatch();
      assign_huge(lower, std::size_t(layout.values(i)));
      const Cascade cascade{s,
                            i,
                            probes[std::size_t(i)],
                            layout.top(i) ? none : probes[std::size_t(i + 1)],
                            upper,
                            lower,
                            bounce == ctx.bounces ? ctx.cache : nullptr};
      report.rays += cascade.run();
      std::swap(upper, lower);
      report.stages.push_back({"cascade " + std::to_string(i) + of, watch.ms()});
    }
    watch = Stopwatch();
    Gather gather{s, probes[0], upper, {}, {}, {}, {}};
    for (int d = 0; d < layout.q0; ++d) {
      gather.screen.push_back(s.directions[0][std::size_t(d)].world);
      if (glossy)
        for (int j = 0; j < cascade::kCellPoints; ++j)
          gather.screen_points.push_back(frame.screen_direction(
              layout.phi(0, d) + 2 * kPi * ((j + 0.5) / cascade::kCellPoints - 0.5) / layout.q0));
    }
    gather.prepare_probes();
    std::uint64_t traced = 0;
    const bool again = bounce < ctx.bounces;
    img =
        shade_pixels(g, bg, traced, [&](int x, int y, std::size_t k, const Hit& h, std::uint64_t&) {
          Rgb l = direct[k], mean;
          if (gather(x, y, k, h, mean)) {
            l += albedo[k] * mean;
            if (glossy && again) next[k] = bounce_direct[k] + bounce_albedo[k] * mean;
          } else if (glossy && again) {
            next[k] = bounce_direct[k];
          }
          if (glossy && alpha[k] >= 0 && gather.lobe(x, y, k, h, alpha[k], mean))
            l += specular[k] * mean;
          return l;
        });
    report.stages.push_back({"gather" + of, watch.ms()});
    if (again)
      for (std::size_t k = 0; k < pixels; ++k)
        if (g.found[k])
          radiance[k] = glossy
                            ? next[k]
                            : img.at(int(k % std::size_t(g.width)), int(k / std::size_t(g.width)));
  }
  return img;
}

}  // namespace penumbra::spaceland::ssrc
