// Holographic radiance cascades (seed 004 section 4). Each quadrant runs the same code on a
// rotated copy of the medium in which it gathers light arriving from +u:
//   T_0..T_2  traced exactly: every probe's ray crosses the same cells, so a gather per cell;
//   T_3..T_N  merged up from the level below (eq. 18 for even directions, eqs. 19-20 for odd);
//   R_N-1..R_0 merged down (eq. 14 for odd x, eqs. 15-17 for even x), R_N the environment.
// The quadrant's fluence at cell [u, v] is R_0([u + 1, v]); the four are summed in the world
// grid, then cross-blurred (eq. 21).
//
// Layout: level n of T (and of R) is a set of columns, one per (direction, probe x), each the
// grid's h rows long, channel after channel. Every read of a merge is then a column at a fixed
// row shift, so the inner loops stream contiguous memory; rows whose shifted read leaves the
// grid read a column of what lies beyond instead (T empty, R the environment), through the same
// loops.
#include "flatland/hrc/hrc.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#if defined(__SSE2__)
#include <xmmintrin.h>
#endif
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include "core/half.hpp"
#include "core/huge_pages.hpp"
#include "core/math.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "flatland/interval.hpp"
#include "flatland/trace.hpp"

namespace penumbra::flatland::hrc {

namespace {

struct Rad {
  float r, g, b;
};

// v_n(k) = (2^n, 2k - 2^n): the offset from a cascade-n probe to the end of its edge ray k.
// (The seed prints k - 2^n; with it the cones would span only -45..0 degrees, and neither
// "v_n(k) is always a multiple of 2 for n >= 1" nor T_2's 4 sqrt 2 longest ray would hold.)
inline int vy(int n, int k) {
  return 2 * k - (1 << n);
}

enum Plane { kR, kG, kB, kTau0, kTau1, kTau2, kPlanes };

// Structure of arrays: plane p holds `cells` floats, column by column (v fastest), like T and R.
struct ViewPlanes {
  float* data = nullptr;
  std::size_t cells = 0;
  int hp = 0;  // column length: h + 2 kPad
  float* plane(int p) { return data + p * cells; }
  const float* plane(int p) const { return data + p * cells; }
  // Offset of view cell (u, v) in a plane.
  std::size_t at(int u, int v) const { return std::size_t(u) * hp + kPad + v; }
};

template <class S>
std::uint64_t bytes_of(const Sizes& s, int width, int height, bool blur) {
  std::uint64_t b = 0;
  for (std::size_t t : s.t) b += t * 4 * sizeof(S);  // radiance and transmittance
  b += 2 * s.r * 3 * sizeof(S);                      // angular fluence
  const std::uint64_t cells = std::uint64_t(width) * height;
  const std::uint64_t world = std::uint64_t(unaliased_stride(width)) * height;
  b += (s.pad + world) * kPlanes * sizeof(float);  // a rotated view and the world planes
  b += cells * 3 * sizeof(float);                  // the summed fluence
  if (blur) b += cells * 3 * sizeof(float);        // its blurred copy
  return b;
}

template <class S>
struct Buffers {
  std::vector<HugeArray<S>> t;
  HugeArray<S> r[2];
  void release() {
    t.clear();
    r[0].release(), r[1].release();
  }
};

// The gather writes a quadrant's fluence into the world grid in tiles of kTile view columns,
// row by row, where a view column is a world column (both sides of the transpose in cache).
constexpr int kTile = 32;

// The medium as planes in world layout (row by row, unaliased_stride() apart), computed once per
// solve: the rotated views are then permutations of it.
void build_world(const Medium& m, int stride, float* planes) {
  const std::size_t cells = std::size_t(stride) * m.height;
  parallel_for(m.height, [&](int y) {
    for (int x = 0; x < m.width; ++x) {
      const std::size_t c_at = std::size_t(y) * m.width + x, i = std::size_t(y) * stride + x;
      const Cell& c = m.cells[c_at];
      const float sigma = m.step[c_at] > 0 ? m.step[c_at] : 0.0f;
      planes[kR * cells + i] = c.r, planes[kG * cells + i] = c.g, planes[kB * cells + i] = c.b;
      // Empty and opaque cells, most of a painted scene, need no exp.
      for (int l = 0; l < 3; ++l)
        planes[(kTau0 + l) * cells + i] = sigma == 0.0f      ? 1.0f
                                          : sigma == kOpaque ? 0.0f
                                                             : std::exp(-sigma * kLengths[l]);
    }
  });
}

void build_view(const float* world, int width, int height, int stride, int d, const View& view,
                ViewPlanes& out) {
  out.hp = view.h + 2 * kPad;
  const std::size_t cells = std::size_t(stride) * height;
  const Rotation rot = rotation(d, width, height, stride);
  const int columns = view.w + kPad;  // kPad empty columns after the view
  // Tiles of kBlock columns, all planes: a view column is a world row read forwards or backwards
  // (|sv| = 1), or a world column, the tile's columns read a whole cache line of each world row
  // at a time (rows unaliased_stride() apart). Wider tiles, or blocks of 64 rows, were slower.
  constexpr int kBlock = 16;
  parallel_for((columns + kBlock - 1) / kBlock, [&](int tile) {
    const int u0 = tile * kBlock, u1 = std::min(columns, u0 + kBlock);
    const int ue = std::min(u1, view.w);
    for (int p = 0; p < kPlanes; ++p) {
      float* dst = out.plane(p);
      const float* src = world + p * cells;
      const float outside = p < kTau0 ? 0.0f : 1.0f;
      // The padding: kPad cells above and below every column, and the empty columns.
      for (int u = u0; u < u1; ++u) {
        float* col = dst + std::size_t(u) * out.hp;
        if (u >= view.w) {
          std::fill(col, col + out.hp, outside);
          continue;
        }
        std::fill(col, col + kPad, outside);
        std::fill(col + kPad + view.h, col + out.hp, outside);
      }
      if (rot.sv == 1 || rot.sv == -1) {
        for (int u = u0; u < ue; ++u) {
          const float* from = src + rot.at(u, 0);
          float* to = dst + out.at(u, 0);
          if (rot.sv == 1)
            std::copy_n(from, view.h, to);
          else
            for (int v = 0; v < view.h; ++v) to[v] = from[-v];
        }
        continue;
      }
      int u4 = u0;  // columns before u4 are done
#if defined(__SSE2__)
      // 4 x 4 blocks: 4 world rows read as vectors (backwards when su = -1) and transposed in
      // registers into 4 view columns, the tile's 16 columns of a row (one cache line) one after
      // the other. Scalar reads of single floats, in 64 x 64 blocks, took 3x a row copy.
      u4 = u0 + (ue - u0) / 4 * 4;
      const int v4 = view.h / 4 * 4;
      for (int v = 0; v < v4; v += 4)
        for (int u = u0; u < u4; u += 4) {
          const float* from = src + rot.at(u, v);  // (u + i, v + k) at from[i su + k sv]
          __m128 r[4];
          for (int k = 0; k < 4; ++k) {
            const float* row = from + k * rot.sv;
            r[k] = rot.su > 0 ? _mm_loadu_ps(row)
                              : _mm_shuffle_ps(_mm_loadu_ps(row - 3), _mm_loadu_ps(row - 3),
                                               _MM_SHUFFLE(0, 1, 2, 3));
          }
          _MM_TRANSPOSE4_PS(r[0], r[1], r[2], r[3]);
          for (int i = 0; i < 4; ++i) _mm_storeu_ps(dst + out.at(u + i, v), r[i]);
        }
      for (int u = u0; u < u4; ++u)
        for (int v = v4; v < view.h; ++v) dst[out.at(u, v)] = src[rot.at(u, v)];
#endif
      for (int u = u4; u < ue; ++u) {
        const float* from = src + rot.at(u, 0);
        float* to = dst + out.at(u, 0);
        for (int v = 0; v < view.h; ++v) to[v] = from[v * rot.sv];
      }
    }
  });
}

// The cells a ray from a cell centre to the cell centre at v_n(k) crosses, with its length in
// each: the same for every probe, so tracing T_0..T_2 is a gather. Found by the tracer's own
// DDA (walk_cells) on a small grid where every cell interacts.
struct Segment {
  int du, dv;
  float len;
  int plane = kTau0;     // the transmittance plane of its length
  bool squared = false;  // twice that length
  int corner = 0;        // +-1: the corner of (du, dv) towards (du + 1, dv) and (du, dv + corner)
};

std::vector<Segment> ray_pattern(int n, int k);

// The patterns of T_0..T_2 (n = 0..2, k = 0..2^n), found once.
using Patterns = std::array<std::array<std::vector<Segment>, 5>, 3>;
const Patterns& ray_patterns() {
  static const Patterns patterns = [] {
    Patterns p;
    for (int n = 0; n < 3; ++n)
      for (int k = 0; k <= (1 << n); ++k) p[n][k] = ray_pattern(n, k);
    return p;
  }();
  return patterns;
}

std::vector<Segment> ray_pattern(int n, int k) {
  constexpr int kSide = 2 * kPad + 1;
  Medium m;
  m.width = m.height = kSide;
  m.cells.assign(std::size_t(kSide) * kSide, Cell{0, 0, 0});
  m.step.assign(std::size_t(kSide) * kSide, 1.0f);
  const float vx = float(1 << n), vv = float(vy(n, k));
  const float len = std::sqrt(vx * vx + vv * vv);
  std::vector<Segment> segs;
  walk_cells(m, kPad + 0.5f, kPad + 0.5f, vx / len, vv / len, 0.0f, len, false,
             [&](std::size_t idx, float, float t0, float t1) {
               if (t1 > t0)
                 segs.push_back({int(idx % kSide) - kPad, int(idx / kSide) - kPad, t1 - t0});
               return true;
             });
  for (Segment& g : segs) {
    float best = 1e30f;
    for (int l = 0; l < 3; ++l)
      for (int sq = 0; sq < 2; ++sq) {
        const float e = std::abs(g.len - kLengths[l] * float(1 + sq));
        if (e < best) best = e, g.plane = kTau0 + l, g.squared = sq;
      }
    // Rays between cell centres with these offsets cross cells only along the six lengths.
    if (best > 1e-4f) throw std::logic_error("hrc: a traced segment of unexpected length");
  }
  // A 45-degree ray passes from cell to cell through their shared corner: between the two cells
  // that touch it, which a wall of cells meeting only at corners (a diagonal line) must not let
  // through. The corner goes between the two cells, for trace_level to apply HrcOptions::corners.
  std::vector<Segment> out;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    if (i > 0 && segs[i].du != segs[i - 1].du && segs[i].dv != segs[i - 1].dv)
      out.push_back({segs[i - 1].du, segs[i - 1].dv, 0, kTau0, false, segs[i].dv - segs[i - 1].dv});
    out.push_back(segs[i]);
  }
  return out;
}

// T and R as columns: column c of a level (one direction and probe x) holds the h rows of its
// first channel, then of the next (structure of arrays: radiance r, g, b and, for T, the
// transmittance), so every loop below streams unit-stride arrays.
constexpr int kTChannels = 4, kRChannels = 3;

// Channel values of row y of a column.
template <class S>
inline Interval get_t(const S* col, int y, int h) {
  return {load(col[y]), load(col[h + y]), load(col[2 * h + y]), load(col[3 * h + y])};
}

template <class S>
inline Rad get_r(const S* col, int y, int h) {
  return {load(col[y]), load(col[h + y]), load(col[2 * h + y])};
}

template <class S>
inline void put_t(S* col, int y, int h, const Interval& v) {
  col[y] = S(v.r), col[h + y] = S(v.g), col[2 * h + y] = S(v.b), col[3 * h + y] = S(v.t);
}

template <class S>
inline void put_r(S* col, int y, int h, float r, float g, float b) {
  col[y] = S(r), col[h + y] = S(g), col[2 * h + y] = S(b);
}

// A read of a merge: column `col` (null: outside the grid) at row shift dy, and the column to
// read instead where the shifted row leaves the grid: a column holding the value beyond the
// grid in every row (T: an empty interval; R: the environment over the cone).
template <class S>
struct Read {
  const S* col;
  int dy;
  const S* outside;
};

// Splits the rows [0, h) at every row where a read enters or leaves its column and calls
// fast(lo, hi, cols, dys) for each piece, with each read either inside its column throughout
// or redirected to its outside column (shift 0), after prepare(i, lo, hi) has had the chance
// to fill rows [lo, hi) of read i's outside column. So every row runs the same vectorised
// loops: no per-row bounds checks.
template <class S, std::size_t K, class Fast, class Prepare>
inline void for_segments(int h, const std::array<Read<S>, K>& reads, Fast&& fast,
                         Prepare&& prepare) {
  std::array<int, 2 * K + 2> cut;
  std::array<int, K> lo, hi;
  std::size_t m = 0;
  cut[m++] = 0;
  cut[m++] = h;
  for (std::size_t i = 0; i < K; ++i) {
    lo[i] = reads[i].col ? std::clamp(-reads[i].dy, 0, h) : h;
    hi[i] = reads[i].col ? std::clamp(h - reads[i].dy, 0, h) : h;
    cut[m++] = lo[i];
    cut[m++] = hi[i];
  }
  std::sort(cut.begin(), cut.begin() + m);
  for (std::size_t c = 0; c + 1 < m; ++c) {
    const int y0 = cut[c], y1 = cut[c + 1];
    if (y0 == y1) continue;
    std::array<const S*, K> cols;
    std::array<int, K> dys;
    for (std::size_t i = 0; i < K; ++i) {
      const bool inside = y0 >= lo[i] && y1 <= hi[i] && lo[i] < hi[i];
      cols[i] = inside ? reads[i].col : reads[i].outside;
      dys[i] = inside ? reads[i].dy : 0;
      if (!inside) prepare(i, y0, y1);
    }
    fast(y0, y1, cols, dys);
  }
}

// One crossed cell for a column of h probes, front to back: a streaming loop over restrict
// pointers, so it vectorises.
template <bool Squared>
void cross_cells(int h, const float* __restrict tau, const float* __restrict er,
                 const float* __restrict eg, const float* __restrict eb, float* __restrict ar,
                 float* __restrict ag, float* __restrict ab, float* __restrict at) {
  for (int v = 0; v < h; ++v) {
    const float tr = Squared ? tau[v] * tau[v] : tau[v], w = at[v] * (1.0f - tr);
    ar[v] += w * er[v], ag[v] += w * eg[v], ab[v] += w * eb[v];
    at[v] *= tr;
  }
}

// A ray through a corner it shares with two cells (Segment::corner), for a column of h probes:
// each opaque one stops half of it, with its emission, the mean over the ray nudged off the
// corner to either side (Corners::half); with Corners::walls only two opaque cells (a diagonal
// wall) stop it. Two opaque cells stop all of it either way.
void cross_corner(int h, Corners rule, const float* __restrict ta, const float* __restrict tb,
                  const float* const ea[3], const float* const eb[3], float* const acc[4]) {
  float* __restrict ar = acc[0], * __restrict ag = acc[1], * __restrict ab = acc[2], * __restrict at = acc[3];
  const bool walls = rule == Corners::walls;
  for (int v = 0; v < h; ++v) {
    // Corners::walls: half for each only when both are opaque.
    const float both = ta[v] == 0.0f && tb[v] == 0.0f ? 0.5f : 0.0f;
    const float oa = walls ? both : ta[v] == 0.0f ? 0.5f : 0.0f;
    const float ob = walls ? both : tb[v] == 0.0f ? 0.5f : 0.0f;
    const float w = at[v];
    ar[v] += w * (oa * ea[0][v] + ob * eb[0][v]);
    ag[v] += w * (oa * ea[1][v] + ob * eb[1][v]);
    ab[v] += w * (oa * ea[2][v] + ob * eb[2][v]);
    at[v] = w * (1.0f - oa - ob);
  }
}

// T_n(p, k) = Trace(p, p + v_n(k)) for n <= 2, by the rays' cell patterns: one pass over a
// column of probes per crossed cell, accumulating front to back in single precision.
template <class S>
void trace_column(const View& view, int n, const ViewPlanes& vp, Corners corners,
                  const std::array<std::vector<Segment>, 5>& patterns, S* out, int k, int x) {
  const int P = view.probes(n), h = view.h, u = x << n;
  thread_local std::vector<float> acc;
  acc.resize(kTChannels * std::size_t(h));
  float *ar = acc.data(), *ag = ar + h, *ab = ag + h, *at = ab + h;
  std::fill(ar, ar + 3 * std::size_t(h), 0.0f);
  std::fill(at, at + h, 1.0f);
  for (const Segment& g : patterns[k]) {
    if (g.corner != 0) {
      const std::size_t a = vp.at(u + g.du + 1, g.dv), b = vp.at(u + g.du, g.dv + g.corner);
      const float* ea[3] = {vp.plane(kR) + a, vp.plane(kG) + a, vp.plane(kB) + a};
      const float* eb[3] = {vp.plane(kR) + b, vp.plane(kG) + b, vp.plane(kB) + b};
      float* acc4[4] = {ar, ag, ab, at};
      cross_corner(h, corners, vp.plane(kTau0) + a, vp.plane(kTau0) + b, ea, eb, acc4);
      continue;
    }
    const std::size_t off = vp.at(u + g.du, g.dv);
    const float *er = vp.plane(kR) + off, *eg = vp.plane(kG) + off, *eb = vp.plane(kB) + off;
    const float* tau = vp.plane(g.plane) + off;
    (g.squared ? cross_cells<true> : cross_cells<false>)(h, tau, er, eg, eb, ar, ag, ab, at);
  }
  S* o = out + (std::size_t(k) * P + x) * kTChannels * h;
  if constexpr (std::is_same_v<S, Half>)
    to_half(acc.data(), o, kTChannels * h);
  else
    std::copy(acc.begin(), acc.end(), o);
}

// The merges over rows [lo, hi) whose reads all lie inside their columns: plain loops over
// restrict pointers (a row shift is an index offset), so the compiler vectorises them.
template <class S>
[[gnu::noinline]] void up_even_rows(int lo, int hi, int h, const S* __restrict near,
                                    const S* __restrict far, int dy, S* __restrict o) {
  for (int y = lo; y < hi; ++y)
    put_t(o, y, h, merge_intervals(get_t(near, y, h), get_t(far, y + dy, h)));
}

template <class S>
[[gnu::noinline]] void up_odd_rows(int lo, int hi, int h, const S* __restrict a1,
                                   const S* __restrict b1, int dy1, const S* __restrict a0,
                                   const S* __restrict b0, int dy0, S* __restrict o) {
  for (int y = lo; y < hi; ++y) {
    const Interval p = merge_intervals(get_t(a1, y, h), get_t(b1, y + dy1, h));
    const Interval m = merge_intervals(get_t(a0, y, h), get_t(b0, y + dy0, h));
    put_t(o, y, h,
          Interval{0.5f * (p.r + m.r), 0.5f * (p.g + m.g), 0.5f * (p.b + m.b), 0.5f * (p.t + m.t)});
  }
}

// Eq. 14 for one row: both halves of the cone.
inline void odd_cone(float ap, float am, const Interval& ep, const Interval& em, const Rad& fp,
                     const Rad& fm, float& r, float& g, float& b) {
  r = ap * ep.r + ep.t * fp.r + am * em.r + em.t * fm.r;
  g = ap * ep.g + ep.t * fp.g + am * em.g + em.t * fm.g;
  b = ap * ep.b + ep.t * fp.b + am * em.b + em.t * fm.b;
}

// Eqs. 15-17 for one row: the cones at p, weighted wd (the seed's mean: 1/2), and the merges
// along the doubled edges, weighted 1 - wd (HrcOptions::even_weight).
inline void even_cone(float ap, float am, float wd, const Interval& ep, const Interval& em,
                      const Rad& f0p, const Rad& f0m, const Rad& f1p, const Rad& f1m, float& r,
                      float& g, float& b) {
  const float we = 1.0f - wd;
  r = wd * (f0p.r + f0m.r) + we * (ap * ep.r + ep.t * f1p.r + am * em.r + em.t * f1m.r);
  g = wd * (f0p.g + f0m.g) + we * (ap * ep.g + ep.t * f1p.g + am * em.g + em.t * f1m.g);
  b = wd * (f0p.b + f0m.b) + we * (ap * ep.b + ep.t * f1p.b + am * em.b + em.t * f1m.b);
}

template <class S>
[[gnu::noinline]] void down_odd_rows(int lo, int hi, int h, float ap, float am,
                                     const S* __restrict tp, const S* __restrict tm,
                                     const S* __restrict rp, int dyp, const S* __restrict rm,
                                     int dym, S* __restrict o) {
  for (int y = lo; y < hi; ++y) {
    float r, g, b;
    odd_cone(ap, am, get_t(tp, y, h), get_t(tm, y, h), get_r(rp, y + dyp, h), get_r(rm, y + dym, h),
             r, g, b);
    put_r(o, y, h, r, g, b);
  }
}

template <class S>
[[gnu::noinline]] void down_even_rows(int lo, int hi, int h, float ap, float am, float wd,
                                      const S* __restrict up, const S* __restrict um,
                                      const S* __restrict r0p, int d0p, const S* __restrict r0m,
                                      int d0m, const S* __restrict r1p, int dyp,
                                      const S* __restrict r1m, int dym, S* __restrict o) {
  for (int y = lo; y < hi; ++y) {
    float r, g, b;
    even_cone(ap, am, wd, get_t(up, y, h), get_t(um, y, h), get_r(r0p, y + d0p, h),
              get_r(r0m, y + d0m, h), get_r(r1p, y + dyp, h), get_r(r1m, y + dym, h), r, g, b);
    put_r(o, y, h, r, g, b);
  }
}

// The half-precision row merges: blocks of kBlock rows of every input (a column, its channel
// count and row shift) are converted to single precision, run through the single-precision loop
// (`rows(n, inputs, out)`, each input then a block with channel stride kBlock), and the result is
// converted back, so the merges still vectorise and memory carries half the bytes.
constexpr int kBlock = 32;

struct HalfInput {
  const Half* col;
  int channels, dy;
};

template <std::size_t K, class Rows>
void half_rows(int lo, int hi, int h, const std::array<HalfInput, K>& in, Half* o, int out_channels,
               Rows&& rows) {
  float blocks[K][kTChannels * kBlock], out[kTChannels * kBlock];
  std::array<const float*, K> f;
  for (std::size_t i = 0; i < K; ++i) f[i] = blocks[i];
  for (int y = lo; y < hi; y += kBlock) {
    const int n = std::min(kBlock, hi - y);
    for (std::size_t i = 0; i < K; ++i)
      for (int c = 0; c < in[i].channels; ++c)
        to_float(in[i].col + std::ptrdiff_t(c) * h + y + in[i].dy, blocks[i] + c * kBlock, n);
    rows(n, f, out);
    for (int c = 0; c < out_channels; ++c)
      to_half(out + c * kBlock, o + std::ptrdiff_t(c) * h + y, n);
  }
}

template <>
void up_even_rows<Half>(int lo, int hi, int h, const Half* near, const Half* far, int dy, Half* o) {
  half_rows<2>(lo, hi, h, {{{near, kTChannels, 0}, {far, kTChannels, dy}}}, o, kTChannels,
               [](int n, const auto& f, float* out) {
                 up_even_rows<float>(0, n, kBlock, f[0], f[1], 0, out);
               });
}

template <>
void up_odd_rows<Half>(int lo, int hi, int h, const Half* a1, const Half* b1, int dy1,
                       const Half* a0, const Half* b0, int dy0, Half* o) {
  half_rows<4>(
      lo, hi, h,
      {{{a1, kTChannels, 0}, {b1, kTChannels, dy1}, {a0, kTChannels, 0}, {b0, kTChannels, dy0}}}, o,
      kTChannels, [](int n, const auto& f, float* out) {
        up_odd_rows<float>(0, n, kBlock, f[0], f[1], 0, f[2], f[3], 0, out);
      });
}

template <>
void down_odd_rows<Half>(int lo, int hi, int h, float ap, float am, const Half* tp, const Half* tm,
                         const Half* rp, int dyp, const Half* rm, int dym, Half* o) {
  half_rows<4>(
      lo, hi, h,
      {{{tp, kTChannels, 0}, {tm, kTChannels, 0}, {rp, kRChannels, dyp}, {rm, kRChannels, dym}}}, o,
      kRChannels, [&](int n, const auto& f, float* out) {
        down_odd_rows<float>(0, n, kBlock, ap, am, f[0], f[1], f[2], 0, f[3], 0, out);
      });
}

template <>
void down_even_rows<Half>(int lo, int hi, int h, float ap, float am, float wd, const Half* up,
                          const Half* um, const Half* r0p, int d0p, const Half* r0m, int d0m,
                          const Half* r1p, int dyp, const Half* r1m, int dym, Half* o) {
  half_rows<6>(lo, hi, h,
               {{{up, kTChannels, 0},
                 {um, kTChannels, 0},
                 {r0p, kRChannels, d0p},
                 {r0m, kRChannels, d0m},
                 {r1p, kRChannels, dyp},
                 {r1m, kRChannels, dym}}},
               o, kRChannels, [&](int n, const auto& f, float* out) {
                 down_even_rows<float>(0, n, kBlock, ap, am, wd, f[0], f[1], f[2], 0, f[3], 0, f[4],
                                       0, f[5], 0, out);
               });
}

// T_{n+1} from T_n: eq. 18 for even directions 2k, eqs. 19-20 for odd ones. `empty` is a column
// of empty intervals (what lies beyond the grid).
template <class S>
void merge_up_column(const View& view, int n, const S* tn, S* tn1, const S* empty, int k2, int x) {
  const int P = view.probes(n), P1 = view.probes(n + 1), h = view.h;
  auto col = [&](int k, int c) -> const S* {
    return c < P ? tn + (std::size_t(k) * P + c) * kTChannels * h : nullptr;
  };
  S* o = tn1 + (std::size_t(k2) * P1 + x) * kTChannels * h;
  if (k2 % 2 == 0) {
    const int k = k2 / 2;
    const S* near = col(k, 2 * x);
    for_segments<S, 1>(
        h, {{{col(k, 2 * x + 1), vy(n, k), empty}}},
        [&](int lo, int hi, const auto& c, const auto& d) {
          up_even_rows(lo, hi, h, near, c[0], d[0], o);
        },
        [](std::size_t, int, int) {});
  } else {
    // Direction k + 1/2 is between two integer ones: average the two bent paths.
    const int k = k2 / 2;
    const S *a1 = col(k + 1, 2 * x), *a0 = col(k, 2 * x);
    for_segments<S, 2>(
        h, {{{col(k, 2 * x + 1), vy(n, k + 1), empty}, {col(k + 1, 2 * x + 1), vy(n, k), empty}}},
        [&](int lo, int hi, const auto& c, const auto& d) {
          up_odd_rows(lo, hi, h, a1, c[0], d[0], a0, c[1], d[1], o);
        },
        [](std::size_t, int, int) {});
  }
}

// T_{n+1} from T_n, every column: eq. 18 for even directions 2k, eqs. 19-20 for odd ones.
// `empty` is a column of empty intervals (what lies beyond the grid).
template <class S>
void merge_up(const View& view, int n, const S* tn, S* tn1, const S* empty) {
  const int P1 = view.probes(n + 1);
  parallel_for(((1 << (n + 1)) + 1) * P1,
               [&](int row) { merge_up_column(view, n, tn, tn1, empty, row / P1, row % P1); });
}

// lower_levels() builds T_0..T_m tile by tile: m as large as keeps a tile's share of a level
// (2^m cells along u by h rows, 16 bytes each in single precision) within kTileBytes, so that
// the level a merge reads and the one it writes stay in each core's cache; at least the traced
// T_0..T_2, at most N.
constexpr std::int64_t kTileBytes = std::int64_t(1) << 18;

int fused_levels(const View& v) {
  int m = 2;
  while (m < v.levels && (std::int64_t(2) << m) * v.h * 16 <= kTileBytes) ++m;
  return std::min(m, v.levels);
}

// T_0..T_m in tiles of 2^m cells along u, each tile traced and merged up to level m before the
// next (T_{n+1} of a tile reads only T_n of the same tile), so the levels a merge reads are
// still in cache from the merge that wrote them: the merges of the lower levels read memory once.
template <class S>
void lower_levels(const View& view, int m, const ViewPlanes& vp, Corners corners,
                  const Patterns& patterns, const std::vector<S*>& t, const S* empty) {
  const int tiles = int((std::int64_t(view.w) + (1 << m) - 1) >> m);
  parallel_for(tiles, [&](int tile) {
    for (int n = 0; n <= m; ++n) {
      const int P = view.probes(n), x0 = tile << (m - n), x1 = std::min(P, (tile + 1) << (m - n));
      for (int k = 0; k <= (1 << n); ++k)
        for (int x = x0; x < x1; ++x) {
          if (n <= 2)
            trace_column(view, n, vp, corners, patterns[std::size_t(n)], t[std::size_t(n)], k, x);
          else
            merge_up_column(view, n - 1, t[std::size_t(n - 1)], t[std::size_t(n)], empty, k, x);
        }
    }
  });
}

// Fills rows [lo, hi) of a column with one value per channel.
template <class S, std::size_t C>
void fill_column(S* col, int h, int lo, int hi, const std::array<float, C>& v) {
  for (std::size_t c = 0; c < C; ++c) std::fill(col + c * h + lo, col + c * h + hi, S(v[c]));
}

// R_n from R_{n+1} (null at n + 1 = N: the environment), T_n and T_{n+1}; wd: the weight of
// the cones at an even column's own probe (HrcOptions::even_weight).
template <class S>
void merge_down(const View& view, int n, const S* tn, const S* tn1, const S* rn1, S* rn,
                const Rgb& env, float wd) {
  const int P = view.probes(n), P1 = view.probes(n + 1), h = view.h;
  auto rcol = [&](int j, int x) -> const S* {
    return rn1 && x < P1 ? rn1 + (std::size_t(j) * P1 + x) * kRChannels * h : nullptr;
  };
  parallel_for((1 << n) * P, [&](int row) {
    const int a = row / P, x = row % P;
    // The upper and lower halves of cone a are cones 2a + 1 and 2a of cascade n + 1; beyond
    // the grid they hold the environment over their angle.
    const float ap = cone_angle(n + 1, 2 * a + 1), am = cone_angle(n + 1, 2 * a);
    thread_local std::vector<S> outside;
    outside.resize(2 * kRChannels * std::size_t(h));
    S *outp = outside.data(), *outm = outp + kRChannels * h;
    // Reads 0 and 2 use the upper half's outside column, 1 and 3 the lower half's (filled only
    // over the rows that read them).
    auto prepare = [&](std::size_t i, int lo, int hi) {
      if (i % 2 == 0)
        fill_column<S, 3>(outp, h, lo, hi, {env.r * ap, env.g * ap, env.b * ap});
      else
        fill_column<S, 3>(outm, h, lo, hi, {env.r * am, env.g * am, env.b * am});
    };
    S* o = rn + std::size_t(row) * kRChannels * h;
    if (x % 2 == 1) {
      // Eq. 14: trace each edge to the cascade-(n+1) probe it ends on, merge with its cone.
      const S* tp = tn + (std::size_t(a + 1) * P + x) * kTChannels * h;
      const S* tm = tn + (std::size_t(a) * P + x) * kTChannels * h;
      const int xq = (x + 1) / 2;
      for_segments<S, 2>(
          h, {{{rcol(2 * a + 1, xq), vy(n, a + 1), outp}, {rcol(2 * a, xq), vy(n, a), outm}}},
          [&](int lo, int hi, const auto& c, const auto& d) {
            down_odd_rows(lo, hi, h, ap, am, tp, tm, c[0], d[0], c[1], d[1], o);
          },
          prepare);
    } else {
      // Eqs. 15-17: T_{n+1} has the same probe columns as R_{n+1}.
      const int xp = x / 2, xq = xp + 1;
      const S* up = tn1 + (std::size_t(2 * a + 2) * P1 + xp) * kTChannels * h;
      const S* um = tn1 + (std::size_t(2 * a) * P1 + xp) * kTChannels * h;
      for_segments<S, 4>(
          h,
          {{{rcol(2 * a + 1, xp), 0, outp},
            {rcol(2 * a, xp), 0, outm},
            {rcol(2 * a + 1, xq), vy(n + 1, 2 * a + 2), outp},
            {rcol(2 * a, xq), vy(n + 1, 2 * a), outm}}},
          [&](int lo, int hi, const auto& c, const auto& d) {
            down_even_rows(lo, hi, h, ap, am, wd, up, um, c[0], d[0], c[1], d[1], c[2], d[2], c[3],
                           d[3], o);
          },
          prepare);
    }
  });
}

// Rows [0, h) of the R_0 read of view column u (R_0 at column u + 1, `edge` beyond the view),
// channel by channel into c[0..2].
template <class S>
void r0_column(const S* r0, const View& view, int u, const Rad& edge, float* const c[3]) {
  const int h = view.h;
  if (u < 0 || u + 1 >= view.w) {
    std::fill(c[0], c[0] + h, edge.r), std::fill(c[1], c[1] + h, edge.g);
    std::fill(c[2], c[2] + h, edge.b);
    return;
  }
  const S* col = r0 + std::size_t(u + 1) * kRChannels * h;
  for (int ch = 0; ch < 3; ++ch)
    for (int v = 0; v < h; ++v) c[ch][v] = load(col[std::size_t(ch) * h + v]);
}

// Eq. 21 over view column u into q[0..2] (rows [0, h)), given the R_0 reads of view columns
// u - 1, u and u + 1 (rd[0..2], channel by channel): 4 at the centre, 1 for each neighbour
// blur_together() admits, beyond the grid none. Column by column so the loops vectorise; `w`
// holds 5 columns.
inline void blur_column(const View& view, const ViewPlanes& vp, int u,
                        const float* const (&rd)[3][3], float* w, float* const q[3]) {
  const int h = view.h;
  // The neighbours' columns (read only where they lie in the view); an opaque cell keeps its
  // value.
  const float* tc = vp.plane(kTau0) + vp.at(u, 0);
  const float* tl = vp.plane(kTau0) + vp.at(std::max(u - 1, 0), 0);
  const float* tr = vp.plane(kTau0) + vp.at(u + 1, 0);
  // w: the four weights, then 1 / their sum with 4
  for (int v = 0; v < h; ++v) {
    const float c = tc[v], opaque = c == 0.0f ? 1.0f : 0.0f;
    const float wl = u > 0 && blur_together(c, tl[v]) ? 1.0f - opaque : 0.0f;
    const float wr = u + 1 < view.w && blur_together(c, tr[v]) ? 1.0f - opaque : 0.0f;
    const float wu = v > 0 && blur_together(c, tc[v - 1]) ? 1.0f - opaque : 0.0f;
    const float wd = v + 1 < h && blur_together(c, tc[v + 1]) ? 1.0f - opaque : 0.0f;
    w[v] = wl, w[h + v] = wr, w[2 * h + v] = wu, w[3 * h + v] = wd;
    w[4 * h + v] = 1.0f / (4.0f + wl + wr + wu + wd);
  }
  for (int ch = 0; ch < 3; ++ch) {
    const float *a = rd[1][ch], *l = rd[0][ch], *r = rd[2][ch];
    float* o = q[ch];
    o[0] = (4.0f * a[0] + w[0] * l[0] + w[h] * r[0] + w[3 * h] * a[h > 1 ? 1 : 0]) * w[4 * h];
    for (int v = 1; v + 1 < h; ++v)
      o[v] = (4.0f * a[v] + w[v] * l[v] + w[h + v] * r[v] + w[2 * h + v] * a[v - 1] +
              w[3 * h + v] * a[v + 1]) *
             w[4 * h + v];
    if (h > 1) {
      const int v = h - 1;
      o[v] = (4.0f * a[v] + w[v] * l[v] + w[h + v] * r[v] + w[2 * h + v] * a[v - 1]) * w[4 * h + v];
    }
  }
}

// The near segment in front of view column u's R_0 read, in place in q[0..2]: from the cell's
// edge across the next cell to its centre, where R_0 is read.
inline void near_column(const View& view, const ViewPlanes& vp, int u, float* const q[3]) {
  const int h = view.h;
  const std::size_t next = vp.at(u + 1, 0);
  const float* t = vp.plane(kTau0) + next;
  const float quarter = float(kPi / 2);
  for (int ch = 0; ch < 3; ++ch) {
    const float* e = vp.plane(kR + ch) + next;
    float* c = q[ch];
    for (int v = 0; v < h; ++v) c[v] = quarter * (1.0f - t[v]) * e[v] + t[v] * c[v];
  }
}

// HrcOptions::wall_fan and near_fan: quadrant d's light at cell (x, y), through 2 rays per cone
// of cascade n, each traced from the cell's centre (leaving an opaque cell) to the first probe
// column of the cascade more than M / 2 cells ahead and merged with its cone of R_n there, read
// between the two rows the ray lands between (beyond the grid: the environment over the cone).
// A quadrant's R_0 is one value for 90 degrees read through the cell beside the wall cell;
// light grazing an edge through the corner of two anti-aliased cells needs the finer cones of
// R_n to reach the wall cell. Near a light's rim, the cones of cascades 0..2 are as coarse for
// its edge. The rays run M / 2 + 1 .. 3M / 2 cells, so that R_n is never read right beside the
// cell, where its own cones are coarse for the same light (the next column, 1..M cells ahead,
// gave 3.94% against 3.77% on the 8-cell light of docs/QUALITY.md).
template <class S>
Rad fan_light(const Medium& m, const View& view, int d, int n, const S* rn, const float* angles,
              const Rgb& env, int x, int y) {
  const int W = m.width, H = m.height;
  int u, v;
  view_cell(d, W, H, x, y, u, v);
  const int M = 1 << n, P = view.probes(n), h = view.h;
  const int xq = (u + M / 2) / M + 1;  // the probe column xq * M
  const float delta = float(xq * M - u);
  const Point a0 = world_point(d, W, H, float(u), float(v));
  const bool open = m.step[std::size_t(y) * W + x] != kOpaque;
  Rad sum{0.0f, 0.0f, 0.0f};
  for (int a = 0; a < M; ++a) {
    const float A = angles[a], outside[3] = {env.r * A, env.g * A, env.b * A};
    const S* col = xq < P ? rn + (std::size_t(a) * P + xq) * kRChannels * h : nullptr;
    auto far = [&](int row, int ch) {
      return !col || row < 0 || row >= h ? outside[ch] : load(col[std::size_t(ch) * h + row]);
    };
    for (int j = 0; j < kWallFanRays; ++j) {
      // Cone a spans the slopes (2a - M) / M .. (2a + 2 - M) / M; ray j the middle of its share.
      const float slope =
          (2.0f * float(a - (M >> 1)) + (2.0f * float(j) + 1.0f) / kWallFanRays) / float(M);
      const float ve = float(v) + slope * delta;
      const Point b = world_point(d, W, H, float(xq * M), ve);
      // From where the ray leaves an open cell: its own medium is added once the quadrants are
      // summed, as for any cell (an opaque one is left by trace_segment).
      float sx = a0.x, sy = a0.y;
      if (open) {
        const float dx = b.x - a0.x, dy = b.y - a0.y;
        const float e = 0.5f / std::max(std::abs(dx), std::abs(dy));
        sx += e * dx, sy += e * dy;
      }
      const Interval seg = trace_segment(m, sx, sy, b.x, b.y, true);
      const int v0 = int(std::floor(ve));
      const float f1 = ve - float(v0), f0 = 1.0f - f1;
      float c[3];
      for (int ch = 0; ch < 3; ++ch)
        c[ch] = f0 * far(v0, ch) + (f1 > 0.0f ? f1 * far(v0 + 1, ch) : 0.0f);
      constexpr float share = 1.0f / kWallFanRays;
      sum.r += share * (A * seg.r + seg.t * c[0]);
      sum.g += share * (A * seg.g + seg.t * c[1]);
      sum.b += share * (A * seg.b + seg.t * c[2]);
    }
  }
  return sum;
}

// With the near segment, a cell's own medium over the light its quadrants gathered (`out`, 3
// floats): the mean over a quadrant's directions of the transmittance from its centre to its
// edge, given `tau` over half a cell. An opaque cell is left as if empty (its fluence is the
// light arriving at it), and an empty one has nothing to add.
inline void add_own_medium(float tau, float r, float g, float b, float* out) {
  if (tau == 0.0f || tau == 1.0f) return;
  const float mo = own_transmittance(tau), e = float(2 * kPi) * (1.0f - mo);
  out[0] = e * r + mo * out[0];
  out[1] = e * g + mo * out[1];
  out[2] = e * b + mo * out[2];
}

// What HrcOptions::wall_fan keeps between solves: the fan's cells and their light.
struct Fan {
  std::vector<std::uint32_t> cells;
  std::vector<float> light;  // 3 per cell, summed over the quadrants
};

template <class S>
void solve_with(const Medium& m, const Rgb& env, const HrcOptions& o, Buffers<S>& buf,
                HugeArray<float>& planes, std::vector<float>& blurred, Fan& fan,
                std::vector<float>& f, std::vector<StageTime>& stages, const float* lights) {
  const int W = m.width, H = m.height;
  const std::size_t cells = std::size_t(W) * H;
  const Sizes sz = plan(W, H);
  buf.t.resize(sz.t.size());
  std::vector<S*> t(sz.t.size());
  for (std::size_t n = 0; n < t.size(); ++n) t[n] = buf.t[n].ensure(sz.t[n] * kTChannels);
  S* r[2] = {buf.r[0].ensure(sz.r * kRChannels), buf.r[1].ensure(sz.r * kRChannels)};
  const int stride = unaliased_stride(W);  // of the world planes
  const std::size_t world_cells = std::size_t(stride) * H;
  float* world = planes.ensure((world_cells + sz.pad) * kPlanes);
  ViewPlanes vp;
  vp.data = world + world_cells * kPlanes;
  vp.cells = sz.pad;
  const Patterns& patterns = ray_patterns();
  reserve_huge(f, cells * 3);
  f.resize(cells * 3);
  std::vector<S> empty;  // a column of empty intervals: what T reads beyond the grid

  Stopwatch watch;
  build_world(m, stride, world);
  double ms_view = watch.ms(), ms_trace = 0, ms_up = 0, ms_down = 0, ms_gather = 0, ms_fan = 0;
  const bool runs = runs_fan(W, H, o);
  if (runs) {
    watch.restart();
    fan_cells(m, lights, o, fan.cells);
    ms_fan += watch.ms();
  } else {
    fan.cells.clear();  // none from an earlier solve on this workspace
  }
  fan.light.assign(fan.cells.size() * 3, 0.0f);
  struct {
    std::uint64_t views = 0, trace = 0, up = 0, down = 0, gather = 0, fan = 0;
  } work;                                // StageTime::work: the values each stage computes
  const float quarter = float(kPi / 2);  // A_0: a quadrant
  for (int d = 0; d < 4; ++d) {
    const View& view = sz.views[d & 1];
    watch.restart();
    build_view(world, W, H, stride, d, view, vp);
    empty.resize(std::size_t(kTChannels) * view.h);
    fill_column<S, 4>(empty.data(), view.h, 0, view.h, {0.0f, 0.0f, 0.0f, 1.0f});
    ms_view += watch.ms();

    watch.restart();
    const int fused = fused_levels(view);
    lower_levels(view, fused, vp, o.corners, patterns, t, empty.data());
    work.views += std::uint64_t(view.w) * view.h;
    work.gather += std::uint64_t(view.w) * view.h;
    for (int n = 0; n <= view.levels; ++n) (n <= fused ? work.trace : work.up) += view.t_size(n);
    for (int n = 0; n < view.levels; ++n) work.down += view.r_size(n);
    ms_trace += watch.ms();
    watch.restart();
    for (int n = fused + 1; n <= view.levels; ++n)
      merge_up(view, n - 1, t[n - 1], t[n], empty.data());
    ms_up += watch.ms();

    watch.restart();
    const S* upper = nullptr;  // R_N: the environment
    const int fan_level = wall_fan_level(view, o.wall_fan);
    for (int n = view.levels - 1; n >= 0; --n) {
      S* out = upper == r[0] ? r[1] : r[0];
      merge_down(view, n, t[n], t[n + 1], upper, out, env, o.even_weight);
      upper = out;
      if (n != fan_level || fan.cells.empty()) continue;
      ms_down += watch.ms();
      watch.restart();
      float angles[1 << kMaxWallFan];
      for (int a = 0; a < 1 << n; ++a) angles[a] = cone_angle(n, a);
      parallel_for(
          int(fan.cells.size()),
          [&](int i) {
            const std::uint32_t c = fan.cells[std::size_t(i)];
            const Rad q = fan_light(m, view, d, n, out, angles, env, int(c % unsigned(W)),
                                    int(c / unsigned(W)));
            float* l = &fan.light[3 * std::size_t(i)];
            l[0] += q.r, l[1] += q.g, l[2] += q.b;
          },
          16);
      ms_fan += watch.ms();
      work.fan += std::uint64_t(fan.cells.size()) * (std::uint64_t(kWallFanRays) << n);
      watch.restart();
    }
    ms_down += watch.ms();

    // The quadrant's fluence at [u, v] is R_0([u + 1, v]): the offset keeps the diagonal rays
    // of neighbouring quadrants apart (seed 004, Fig. 12). With the near segment, the transport
    // from the cell's edge to that probe comes first; the cell's own part, the same for every
    // quadrant, is added with the last one. Eq. 21 blurs R_0 here unless it is to blur the whole
    // fluence (blur_near, after the loop).
    watch.restart();
    const S* r0 = upper;
    const Rad edge{env.r * quarter, env.g * quarter, env.b * quarter};
    const Rotation rot = rotation(d, W, H);
    const bool blur_far = blurs_far_light(o), own = o.near_segment && d == 3;
    const int h = view.h;
    const bool rows = rot.sv == 1 || rot.sv == -1;  // a view column is a world row
    const int strip = rows ? 1 : kTile;             // columns gathered before writing the world
    parallel_for((view.w + strip - 1) / strip, [&](int t) {
      const int u0 = t * strip, u1 = std::min(view.w, u0 + strip);
      thread_local std::vector<float> buf;
      buf.resize(14 * std::size_t(h) + 3 * std::size_t(strip) * h);
      // The R_0 reads of three consecutive view columns, in a ring (each column read once),
      // then the blur's weights.
      auto read = [&](int c) {
        float* slot = buf.data() + std::size_t((c % 3 + 3) % 3) * 3 * h;
        return std::array<float*, 3>{slot, slot + h, slot + 2 * std::size_t(h)};
      };
      auto load = [&](int c) {
        const std::array<float*, 3> at = read(c);
        r0_column(r0, view, c, edge, at.data());
      };
      float* weights = buf.data() + 9 * std::size_t(h);
      float* cols = buf.data() + 14 * std::size_t(h);
      if (blur_far) load(u0 - 1), load(u0);
      for (int u = u0; u < u1; ++u) {
        float* qc = cols + std::size_t(u - u0) * 3 * h;
        float* q[3] = {qc, qc + h, qc + 2 * h};
        if (blur_far) {
          load(u + 1);
          const std::array<float*, 3> l = read(u - 1), c = read(u), r = read(u + 1);
          const float* const rd[3][3] = {
              {l[0], l[1], l[2]}, {c[0], c[1], c[2]}, {r[0], r[1], r[2]}};
          blur_column(view, vp, u, rd, weights, q);
        } else {
          r0_column(r0, view, u, edge, q);
        }
        if (o.near_segment) near_column(view, vp, u, q);
      }
      // The cell's own part, once the four quadrants are summed: an opaque own cell is left as if
      // empty (its fluence is the light arriving at it).
      auto put = [&](int u, int v) {
        const float* qc = cols + std::size_t(u - u0) * 3 * h;
        float* out = &f[std::size_t(rot.at(u, v)) * 3];
        if (d == 0) {
          out[0] = qc[v], out[1] = qc[h + v], out[2] = qc[2 * h + v];
          return;
        }
        out[0] += qc[v], out[1] += qc[h + v], out[2] += qc[2 * h + v];
        if (!own) return;
        const std::size_t at = vp.at(u, v);
        add_own_medium(vp.plane(kTau0)[at], vp.plane(kR)[at], vp.plane(kG)[at], vp.plane(kB)[at],
                       out);
      };
      if (rows)
        for (int v = 0; v < h; ++v) put(u0, v);
      else
        for (int v = 0; v < h; ++v)
          for (int u = u0; u < u1; ++u) put(u, v);
    });
    ms_gather += watch.ms();
  }
  // The fan's cells take its light in place of what their quadrants read, then an open cell's
  // own medium as the gather adds it (with the near segment, the mean over a quadrant's
  // directions: exact for a lone glowing cell).
  for (std::size_t i = 0; i < fan.cells.size(); ++i) {
    const std::uint32_t c = fan.cells[i];
    float* out = &f[3 * std::size_t(c)];
    std::copy_n(&fan.light[3 * i], 3, out);
    if (!o.near_segment) continue;
    const float* w = world + std::size_t(c / unsigned(W)) * stride + c % unsigned(W);
    add_own_medium(w[kTau0 * world_cells], w[kR * world_cells], w[kG * world_cells],
                   w[kB * world_cells], out);
  }
  stages.push_back({"views", ms_view, work.views});
  stages.push_back({"gather", ms_gather, work.gather});
  if (runs) stages.push_back({"fan", ms_fan, work.fan});
  stages.push_back({"trace T0-T2", ms_trace, work.trace});
  stages.push_back({"merge up T3-TN", ms_up, work.up});
  stages.push_back({"merge down R", ms_down, work.down});
  if (blurs_whole_fluence(o)) {
    watch.restart();
    reserve_huge(blurred, cells * 3);
    blurred.resize(cells * 3);
    cross_blur(W, H, world + kTau0 * world_cells, stride, f.data(), blurred.data());
    std::swap(f, blurred);
    stages.push_back({"cross blur", watch.ms(), cells});
  }
}

}  // namespace

// ---- the geometry shared with the GPU backend (hrc.hpp) ---------------------------------------

float own_transmittance(float t) {
  // Nodes a_i = pi/8 (1 + x_i) as 1 / cos a_i, and weights w_i / 2 (the mean over pi/4).
  constexpr float kSec[4] = {1.001488695f, 1.034556040f, 1.156447476f, 1.343009689f};
  constexpr float kWeight[4] = {0.17392742255f, 0.32607257745f, 0.32607257745f, 0.17392742255f};
  if (t == 1.0f) return 1.0f;  // empty: most cells
  const float l = std::log(t);
  float m = 0;
  for (int i = 0; i < 4; ++i) m += kWeight[i] * std::exp(l * kSec[i]);
  return m;
}

std::size_t fan_budget(int width, int height, const HrcOptions& o) {
  if (!runs_fan(width, height, o)) return 0;
  const double cells = double(width) * double(height);
  const double share = std::ceil(double(o.fan_share) * cells);
  return std::size_t(std::min(std::max(share, double(kMinFanCells)), cells));
}

namespace {

// fan_cells on a grid whose cell i is opaque when opaque(i), and emits when emits(i).
template <class Opaque, class Emits>
void rank_fan_cells(int W, int H, const HrcOptions& o, Opaque opaque, Emits emits,
                    std::vector<std::uint32_t>& cells) {
  const std::size_t budget = fan_budget(W, H, o);
  cells.clear();
  if (budget == 0) return;
  const int K = std::clamp(o.near_fan, 0, kMaxNearFan);
  const std::size_t N = std::size_t(W) * H;
  auto at = [W](int x, int y) { return std::size_t(y) * W + x; };
  // Whether any cell of the 3x3 around (x, y), within the grid, passes `test`.
  auto around = [&](int x, int y, auto test) {
    for (int b = std::max(y - 1, 0); b <= std::min(y + 1, H - 1); ++b)
      for (int a = std::max(x - 1, 0); a <= std::min(x + 1, W - 1); ++a)
        if (test(at(a, b))) return true;
    return false;
  };
  // A cell's rank: 0 a lit wall cell or a rim, d the distance along x and y to the nearest rim
  // up to K, then K + 1 the other open cells (farther from a rim, where the fan's rays do no
  // better than the cascades and somewhat worse far from lights, docs/QUALITY.md) and K + 2
  // the cells inside walls (where the fan gives what the quadrants give, but its rays stop at
  // once: taken before them, a budget larger than a scene needs would cost it less than an
  // empty grid, 0.8x of the fan's time with 2 lights).
  const std::uint8_t far = std::uint8_t(K + 1), inside = std::uint8_t(K + 2);
  std::vector<std::uint8_t> rank(N);
  parallel_for(H, [&](int y) {
    for (int x = 0; x < W; ++x) {
      const std::size_t i = at(x, y);
      const bool rim = emits(i) && around(x, y, [&](std::size_t j) { return !emits(j); });
      rank[i] = rim ? 0 : far;
    }
  });
  // The distance along x and y (chessboard) to the nearest rim, up to K: along each row first
  // (K + 1: none within K), then the nearest of the rows within K (rows in parallel both ways).
  if (K > 0) {
    std::vector<std::uint8_t> along(N);
    parallel_for(H, [&](int y) {
      int last = -K - 1;  // the last rim at or left of x, then the next at or right of it
      for (int x = 0; x < W; ++x) {
        if (rank[at(x, y)] == 0) last = x;
        along[at(x, y)] = std::uint8_t(std::min(x - last, K + 1));
      }
      for (int x = W - 1, next = W + K + 1; x >= 0; --x) {
        if (rank[at(x, y)] == 0) next = x;
        along[at(x, y)] = std::min(along[at(x, y)], std::uint8_t(std::min(next - x, K + 1)));
      }
    });
    parallel_for(H, [&](int y) {
      for (int x = 0; x < W; ++x) {
        int d = K + 1;
        for (int b = std::max(y - K, 0); b <= std::min(y + K, H - 1); ++b)
          d = std::min(d, std::max(std::abs(b - y), int(along[at(x, b)])));
        if (d <= K) rank[at(x, y)] = std::uint8_t(d);
      }
    });
  }
  parallel_for(H, [&](int y) {
    for (int x = 0; x < W; ++x) {
      const std::size_t i = at(x, y);
      if (!opaque(i)) continue;  // a rim within K, or far
      rank[i] = around(x, y, [&](std::size_t j) { return !opaque(j); }) ? 0 : inside;
    }
  });
  // The rank the budget ends in, and how many of its cells it takes (in row order): counted
  // row by row, so the cells come out in the same order on any thread count.
  const int ranks = K + 3;
  std::vector<std::uint32_t> count(std::size_t(H) * ranks, 0);
  parallel_for(H, [&](int y) {
    std::uint32_t* c = &count[std::size_t(y) * ranks];
    for (int x = 0; x < W; ++x) ++c[rank[at(x, y)]];
  });
  std::vector<std::size_t> total(ranks, 0);
  for (int y = 0; y < H; ++y)
    for (int r = 0; r < ranks; ++r) total[r] += count[std::size_t(y) * ranks + r];
  int last = 0;
  std::size_t before = 0;  // cells of the ranks below `last`
  while (before + total[last] < budget) before += total[last++];
  // Per row: its first index in the list, and how many of its cells of rank `last` go in.
  std::vector<std::size_t> first(std::size_t(H) + 1, 0), ties(std::size_t(H), 0);
  std::size_t left = budget - before;
  for (int y = 0; y < H; ++y) {
    const std::uint32_t* c = &count[std::size_t(y) * ranks];
    std::size_t below = 0;
    for (int r = 0; r < last; ++r) below += c[r];
    ties[y] = std::min<std::size_t>(c[last], left);
    left -= ties[y];
    first[std::size_t(y) + 1] = first[std::size_t(y)] + below + ties[y];
  }
  cells.resize(budget);
  parallel_for(H, [&](int y) {
    std::size_t i = first[std::size_t(y)], tie = ties[std::size_t(y)];
    for (int x = 0; x < W; ++x) {
      const int r = rank[at(x, y)];
      bool take = r < last;
      if (r == last && tie > 0) take = true, --tie;
      if (take) cells[i++] = std::uint32_t(at(x, y));
    }
  });
}

}  // namespace

void fan_cells(const Medium& m, const float* lights, const HrcOptions& o,
               std::vector<std::uint32_t>& cells) {
  rank_fan_cells(
      m.width, m.height, o, [&](std::size_t i) { return m.step[i] == kOpaque; },
      [&](std::size_t i) {
        if (lights) return lights[3 * i] + lights[3 * i + 1] + lights[3 * i + 2] > 0.0f;
        const Cell& c = m.cells[i];
        return c.r + c.g + c.b > 0.0f;
      },
      cells);
}

void fan_cells(const Scene& s, const HrcOptions& o, std::vector<std::uint32_t>& cells) {
  const float* e = s.emission.data();
  rank_fan_cells(
      s.width, s.height, o, [&](std::size_t i) { return s.opacity[i] >= 1.0f; },
      [&](std::size_t i) { return e[3 * i] + e[3 * i + 1] + e[3 * i + 2] > 0.0f; }, cells);
}

float cone_angle(int n, int a) {
  const double s = double(1 << n);
  return float(std::atan2(2.0 * (a + 1) - s, s) - std::atan2(2.0 * a - s, s));
}

View make_view(int w, int h) {
  return {w, h, level_count(w)};
}

Sizes plan(int width, int height) {
  Sizes s;
  s.views[0] = make_view(width, height);
  s.views[1] = make_view(height, width);
  const int levels = std::max(s.views[0].levels, s.views[1].levels);
  s.t.assign(std::size_t(levels) + 1, 0);
  for (const View& v : s.views) {
    for (int n = 0; n <= v.levels; ++n) s.t[n] = std::max(s.t[n], v.t_size(n));
    for (int n = 0; n < v.levels; ++n) s.r = std::max(s.r, v.r_size(n));
    s.pad = std::max(s.pad, std::size_t(v.w + kPad) * (v.h + 2 * kPad));
  }
  return s;
}

Rotation rotation(int d, int width, int height, std::ptrdiff_t stride) {
  const std::ptrdiff_t W = width, S = stride ? stride : W,
                       last_row = std::ptrdiff_t(height - 1) * S;
  switch (d) {
    case 0:
      return {0, 1, S};  // (x, y) = (u, v)
    case 1:
      return {W - 1, S, -1};  // (x, y) = (W - 1 - v, u)
    case 2:
      return {last_row + W - 1, -1, -S};  // (x, y) = (W - 1 - u, H - 1 - v)
    default:
      return {last_row, -S, 1};  // (x, y) = (v, H - 1 - u)
  }
}

Point world_point(int d, int width, int height, float u, float v) {
  const float W = float(width - 1), H = float(height - 1);
  const Point p = d == 0   ? Point{u, v}
                  : d == 1 ? Point{W - v, u}
                  : d == 2 ? Point{W - u, H - v}
                           : Point{v, H - u};
  return {p.x + 0.5f, p.y + 0.5f};
}

void view_cell(int d, int width, int height, int x, int y, int& u, int& v) {
  u = d == 0 ? x : d == 1 ? y : d == 2 ? width - 1 - x : height - 1 - y;
  v = d == 0 ? y : d == 1 ? width - 1 - x : d == 2 ? height - 1 - y : x;
}

int unaliased_stride(int n) {
  // A multiple of 16 floats (whole cache lines) that is not a multiple of 256: rows 1 KiB or
  // 4 KiB apart fall into the same L1 set, and a transposing read of 16 rows missed L1 every
  // time (views at 1024^2 took 8x those at 512^2).
  const int s = (n + 15) / 16 * 16;
  return s % 256 == 0 ? s + 16 : s;
}

std::vector<TracedCell> traced_cells(int n, int k) {
  std::vector<TracedCell> out;
  for (const Segment& g : ray_patterns()[std::size_t(n)][std::size_t(k)])
    out.push_back({g.du, g.dv, g.plane - kTau0, g.squared, g.corner});
  return out;
}

int level_count(int w) {
  int n = 0;
  while ((std::int64_t(1) << n) < w) ++n;
  return n;
}

std::uint64_t working_bytes(int width, int height, const HrcOptions& o) {
  const Sizes s = plan(width, height);
  // The blur of the whole fluence writes a copy.
  std::uint64_t b = o.storage == Storage::f16
                        ? bytes_of<Half>(s, width, height, blurs_whole_fluence(o))
                        : bytes_of<float>(s, width, height, blurs_whole_fluence(o));
  // The fan: an index and a light per cell it gathers, and the two bytes per cell (a rank, a
  // distance along the row) and the counts per row and rank it chooses them with.
  if (runs_fan(width, height, o))
    b += fan_budget(width, height, o) * (4 + 3 * sizeof(float)) +
         std::uint64_t(width) * height * 2 +
         std::uint64_t(height) * ((kMaxNearFan + 3) * 4 + 2 * sizeof(std::size_t));
  return b;
}

std::uint64_t structure_bytes(int width, int height, Storage storage) {
  const Sizes s = plan(width, height);
  const std::uint64_t size = storage == Storage::f16 ? sizeof(Half) : sizeof(float);
  const std::uint64_t vt = kTChannels * size, vr = kRChannels * size;
  std::uint64_t b = 2 * s.r * vr;
  for (std::size_t t : s.t) b += t * vt;
  return b;
}

std::uint64_t paper_bytes(int width, int height, const HrcOptions& o) {
  const int n = level_count(std::max(width, height));
  const double vr = 3.0 * (o.storage == Storage::f16 ? 2 : 4), vt = vr / 3;
  const double four_n = std::ldexp(1.0, 2 * n);
  return std::uint64_t((n + 3 + std::ldexp(1.0, -n)) * four_n * (vr + vt) + 2 * four_n * vr);
}

std::uint64_t traced_intervals(int width, int height) {
  std::uint64_t total = 0;
  for (int d = 0; d < 4; ++d) {
    const View v = d % 2 == 0 ? make_view(width, height) : make_view(height, width);
    for (int n = 0; n <= std::min(2, v.levels); ++n) total += v.t_size(n);
  }
  return total;
}

struct Workspace::Impl {
  Buffers<float> f32;
  Buffers<Half> f16;
  HugeArray<float> planes;
  std::vector<float> blurred;
  Fan fan;
};

Workspace::Workspace() : impl_(std::make_unique<Impl>()) {}
Workspace::~Workspace() = default;
Workspace::Workspace(Workspace&&) noexcept = default;
Workspace& Workspace::operator=(Workspace&&) noexcept = default;

void solve(const Medium& medium, const Rgb& environment, const HrcOptions& options,
           Workspace& workspace, std::vector<float>& fluence, std::vector<StageTime>& stages,
           const float* lights) {
  Workspace::Impl& w = *workspace.impl_;
  if (options.storage == Storage::f16) {
    w.f32.release();
    solve_with(medium, environment, options, w.f16, w.planes, w.blurred, w.fan, fluence, stages,
               lights);
  } else {
    w.f16.release();
    solve_with(medium, environment, options, w.f32, w.planes, w.blurred, w.fan, fluence, stages,
               lights);
  }
}

// Eq. 21: the 1-cell cross blur (4 at the centre, 1 at each side, over 8), leaving out
// neighbours whose opacity differs from the cell's by more than kBlurOpacityStep (and those
// beyond the grid), renormalised. Opacity over a cell length is 1 - tau(1/2)^2. Opaque cells
// neither blur nor are blurred into others: their fluence is the light arriving at their faces,
// and inside a wall it is zero, so averaging a wall's surface with its inside would darken the
// light it re-emits.

void cross_blur(int W, int H, const float* tau_half, int tau_stride, const float* f, float* out) {
  parallel_for(H, [&](int y) {
    for (int x = 0; x < W; ++x) {
      const std::size_t i = std::size_t(y) * W + x;
      const float tau = tau_half[std::size_t(y) * tau_stride + x];
      if (tau == 0.0f) {  // opaque: kept as it is
        std::copy(f + 3 * i, f + 3 * i + 3, out + 3 * i);
        continue;
      }
      float r = 4 * f[3 * i], g = 4 * f[3 * i + 1], b = 4 * f[3 * i + 2], w = 4;
      auto add = [&](int nx, int ny) {
        if (nx < 0 || ny < 0 || nx >= W || ny >= H) return;
        const std::size_t j = std::size_t(ny) * W + nx;
        if (!blur_together(tau, tau_half[std::size_t(ny) * tau_stride + nx])) return;
        r += f[3 * j], g += f[3 * j + 1], b += f[3 * j + 2], w += 1;
      };
      add(x - 1, y);
      add(x + 1, y);
      add(x, y - 1);
      add(x, y + 1);
      out[3 * i] = r / w, out[3 * i + 1] = g / w, out[3 * i + 2] = b / w;
    }
  });
}

}  // namespace penumbra::flatland::hrc
