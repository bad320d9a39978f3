// Holographic radiance cascades (seed 004 section 4). Each quadrant runs the same code on a
// rotated copy of the medium in which it gathers light arriving from +u:
//   T_0..T_2  traced exactly: every probe's ray crosses the same cells, so a gather per cell;
//   T_3..T_N  merged up from the level below (eq. 18 for even directions, eqs. 19-20 for odd);
//   R_N-1..R_0 merged down (eq. 14 for odd x, eqs. 15-17 for even x), R_N the environment.
// The quadrant's fluence at cell [u, v] is R_0([u + 1, v]); the four are summed in the world
// grid, then cross-blurred (eq. 21).
//
// Layout: level n of T (and of R) is a set of columns, one per (direction, probe x), each the
// grid's h rows long. Every read of a merge is then a column at a fixed row shift, so the inner
// loops stream contiguous memory; only rows whose shifted read leaves the grid take the checked
// path, where T is empty and R is the environment.
#include "flatland/hrc/hrc.hpp"

#include <Imath/half.h>
#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <memory>
#include <new>
#include <string>
#include <type_traits>
#include <utility>

#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "flatland/interval.hpp"
#include "flatland/trace.hpp"

namespace penumbra::hrc {

namespace {

using Half = Imath::half;

inline float load(float v) {
  return v;
}
inline float load(Half v) {
  return float(v);
}

// An interval of T (radiance and transmittance) and a cone of R (angular fluence), in the
// storage precision.
template <class S>
struct TVal {
  S r, g, b, t;
};
template <class S>
struct RVal {
  S r, g, b;
};

struct Rad {
  float r, g, b;
};

// v_n(k) = (2^n, 2k - 2^n): the offset from a cascade-n probe to the end of its edge ray k.
// (The seed prints k - 2^n; with it the cones would span only -45..0 degrees, and neither
// "v_n(k) is always a multiple of 2 for n >= 1" nor T_2's 4 sqrt 2 longest ray would hold.)
inline int vy(int n, int k) {
  return 2 * k - (1 << n);
}

// Eq. 13: the angle of cone a (the paper's i = a + 1/2) of cascade n.
float cone_angle(int n, int a) {
  const double s = double(1 << n);
  return float(std::atan2(2.0 * (a + 1) - s, s) - std::atan2(2.0 * a - s, s));
}

// One quadrant's rotated grid: w cells along the gathering direction (+u), h across.
struct View {
  int w = 0, h = 0;
  int levels = 0;                                                                 // N
  int probes(int n) const { return int((std::int64_t(w) + (1 << n) - 1) >> n); }  // P_n
  std::size_t t_size(int n) const { return std::size_t(probes(n)) * ((1 << n) + 1) * h; }
  std::size_t r_size(int n) const { return std::size_t(probes(n)) * (1 << n) * h; }
};

View make_view(int w, int h) {
  return {w, h, level_count(w)};
}

// Rotated views carry this many empty cells beyond the grid (the longest traced ray, T_2's
// (4, +-4), ends 4 cells out), so the traced levels read them without bounds checks.
constexpr int kPad = 5;

// The rays of T_0..T_2 cross cells along 6 lengths: 1/2, sqrt5/4, sqrt2/2 and their doubles.
// A rotated view keeps, per cell, the emission and the transmittance over the three short
// ones (the doubles are their squares), so tracing is multiply-adds: no exp, no branch, the
// same work whatever the scene holds. Opaque cells have transmittance 0 (e^-inf).
constexpr float kLengths[3] = {0.5f, 0.559016994f, 0.707106781f};
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

// Everything solve() allocates, sized for both view orientations: working_bytes() and solve()
// agree by construction.
struct Sizes {
  View views[2];
  std::vector<std::size_t> t;  // elements of T_n, n = 0..N
  std::size_t r = 0;           // elements of one R layer
  std::size_t pad = 0;         // cells of the rotated medium
};

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

template <class S>
std::uint64_t bytes_of(const Sizes& s, int width, int height, bool blur) {
  std::uint64_t b = 0;
  for (std::size_t t : s.t) b += t * sizeof(TVal<S>);
  b += 2 * s.r * sizeof(RVal<S>);
  const std::uint64_t cells = std::uint64_t(width) * height;
  b += (s.pad + cells) * kPlanes * sizeof(float);  // a rotated view and the world planes
  b += cells * 3 * sizeof(float);                  // the summed fluence
  if (blur) b += cells * 3 * sizeof(float);        // its blurred copy
  return b;
}

// An uninitialised array that only grows (see Workspace). Large ones are aligned to and
// advised as 2 MiB pages: a first solve then takes 512 times fewer page faults (they cost more
// than the arithmetic in a virtual machine), and the merges' strided columns fewer TLB misses.
struct FreeDeleter {
  void operator()(void* p) const { std::free(p); }
};

template <class T>
struct Array {
  std::unique_ptr<T, FreeDeleter> p;
  std::size_t n = 0;
  T* ensure(std::size_t m) {
    static_assert(std::is_trivially_default_constructible_v<T>);
    if (n >= m) return p.get();
    p.reset();
    constexpr std::size_t kHuge = std::size_t(2) << 20;
    const std::size_t bytes = std::max<std::size_t>(m * sizeof(T), 1);
    const std::size_t align = bytes >= 2 * kHuge ? kHuge : 64;
    void* mem = std::aligned_alloc(align, (bytes + align - 1) / align * align);
    if (!mem) throw std::bad_alloc();
    if (align == kHuge) madvise(mem, (bytes + align - 1) / align * align, MADV_HUGEPAGE);
    p.reset(static_cast<T*>(mem));
    n = m;
    return p.get();
  }
  void release() { p.reset(), n = 0; }
};

template <class S>
struct Buffers {
  std::vector<Array<TVal<S>>> t;
  Array<RVal<S>> r[2];
  void release() {
    t.clear();
    r[0].release(), r[1].release();
  }
};

// Where view cell (u, v) of quadrant d = +x, +y, -x, -y lies in a row-major world array:
// base + u * su + v * sv. The rotation takes the quadrant's direction to +u (a rotation, not a
// mirror, so a rotated scene permutes the quadrants and nothing else).
struct Rotation {
  std::ptrdiff_t base, su, sv;
  std::ptrdiff_t at(int u, int v) const { return base + u * su + v * sv; }
};

Rotation rotation(int d, int width, int height) {
  const std::ptrdiff_t W = width, last_row = std::ptrdiff_t(height - 1) * W;
  switch (d) {
    case 0:
      return {0, 1, W};  // (x, y) = (u, v)
    case 1:
      return {W - 1, W, -1};  // (x, y) = (W - 1 - v, u)
    case 2:
      return {last_row + W - 1, -1, -W};  // (x, y) = (W - 1 - u, H - 1 - v)
    default:
      return {last_row, -W, 1};  // (x, y) = (v, H - 1 - u)
  }
}

// Calls f(u, v) for every cell of a w x h view in an order that reads and writes memory in
// runs: along v when the world neighbour of a v step is adjacent (|sv| = 1), otherwise in
// tiles of kTile columns, row by row, so both sides of the transpose stay in cache.
constexpr int kTile = 16;

template <class F>
void for_view_cells(const Rotation& rot, int w, int h, F&& f) {
  if (rot.sv == 1 || rot.sv == -1) {
    parallel_for(w, [&](int u) {
      for (int v = 0; v < h; ++v) f(u, v);
    });
    return;
  }
  parallel_for((w + kTile - 1) / kTile, [&](int tile) {
    const int u0 = tile * kTile, u1 = std::min(w, u0 + kTile);
    for (int v = 0; v < h; ++v)
      for (int u = u0; u < u1; ++u) f(u, v);
  });
}

// The medium as planes in world layout (row by row), computed once per solve: the rotated
// views are then permutations of it.
void build_world(const Medium& m, float* planes) {
  const std::size_t cells = std::size_t(m.width) * m.height;
  parallel_for(m.height, [&](int y) {
    for (int x = 0; x < m.width; ++x) {
      const std::size_t i = std::size_t(y) * m.width + x;
      const Cell& c = m.cells[i];
      const float sigma = m.step[i] > 0 ? m.step[i] : 0.0f;
      planes[kR * cells + i] = c.r, planes[kG * cells + i] = c.g, planes[kB * cells + i] = c.b;
      for (int l = 0; l < 3; ++l) planes[(kTau0 + l) * cells + i] = std::exp(-sigma * kLengths[l]);
    }
  });
}

void build_view(const float* world, int width, int height, int d, const View& view,
                ViewPlanes& out) {
  out.hp = view.h + 2 * kPad;
  const std::size_t cells = std::size_t(width) * height;
  const Rotation rot = rotation(d, width, height);
  for (int p = 0; p < kPlanes; ++p) {
    float* dst = out.plane(p);
    const float* src = world + p * cells;
    const float outside = p < kTau0 ? 0.0f : 1.0f;
    // The padding: kPad cells above and below every column, and kPad empty columns after.
    parallel_for(view.w + kPad, [&](int u) {
      float* col = dst + std::size_t(u) * out.hp;
      if (u >= view.w) {
        std::fill(col, col + out.hp, outside);
        return;
      }
      std::fill(col, col + kPad, outside);
      std::fill(col + kPad + view.h, col + out.hp, outside);
    });
    for_view_cells(rot, view.w, view.h,
                   [&](int u, int v) { dst[out.at(u, v)] = src[rot.at(u, v)]; });
  }
}

// The cells a ray from a cell centre to the cell centre at v_n(k) crosses, with its length in
// each: the same for every probe, so tracing T_0..T_2 is a gather. Found by the tracer's own
// DDA (walk_cells) on a small grid where every cell interacts.
struct Segment {
  int du, dv;
  float len;
  int plane = kTau0;     // the transmittance plane of its length
  bool squared = false;  // twice that length
};

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
  }
  return segs;
}

// Runs f<checked>(y) for every row y in [0, h): unchecked where every (column, row shift) read
// in `reads` stays inside its column, checked elsewhere (a null column is all outside).
template <class F>
inline void for_rows(int h, std::initializer_list<std::pair<const void*, int>> reads, F&& f) {
  int lo = 0, hi = h;
  for (const auto& [col, dy] : reads) {
    if (!col) lo = hi = h;
    lo = std::max(lo, -dy);
    hi = std::min(hi, h - dy);
  }
  lo = std::min(lo, h);
  hi = std::max(hi, lo);
  for (int y = 0; y < lo; ++y) f.template operator()<true>(y);
  for (int y = lo; y < hi; ++y) f.template operator()<false>(y);
  for (int y = hi; y < h; ++y) f.template operator()<true>(y);
}

// T outside the grid: nothing there (the ray has left and does not come back).
template <bool Checked, class S>
inline Interval get_t(const TVal<S>* col, int y, int h) {
  if constexpr (Checked)
    if (!col || y < 0 || y >= h) return Interval::empty();
  const TVal<S>& v = col[y];
  return {load(v.r), load(v.g), load(v.b), load(v.t)};
}

// R outside the grid, or at level N: the environment over the cone (footnote 1).
template <bool Checked, class S>
inline Rad get_r(const RVal<S>* col, int y, int h, const Rad& outside) {
  if constexpr (Checked)
    if (!col || y < 0 || y >= h) return outside;
  const RVal<S>& v = col[y];
  return {load(v.r), load(v.g), load(v.b)};
}

template <class S>
inline void put(TVal<S>& o, const Interval& v) {
  o = {S(v.r), S(v.g), S(v.b), S(v.t)};
}

template <class S>
inline void put(RVal<S>& o, float r, float g, float b) {
  o = {S(r), S(g), S(b)};
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

// T_n(p, k) = Trace(p, p + v_n(k)) for n <= 2, by the rays' cell patterns: one pass over a
// column of probes per crossed cell, accumulating front to back.
template <class S>
void trace_level(const View& view, int n, const ViewPlanes& vp,
                 const std::vector<Segment>* patterns, TVal<S>* out) {
  const int P = view.probes(n), h = view.h;
  parallel_for(((1 << n) + 1) * P, [&](int row) {
    const int k = row / P, u = (row % P) << n;
    thread_local std::vector<float> acc;
    acc.resize(4 * std::size_t(h));
    float *ar = acc.data(), *ag = ar + h, *ab = ag + h, *at = ab + h;
    std::fill(ar, ar + 3 * std::size_t(h), 0.0f);
    std::fill(at, at + h, 1.0f);
    for (const Segment& g : patterns[k]) {
      const std::size_t off = vp.at(u + g.du, g.dv);
      const float *er = vp.plane(kR) + off, *eg = vp.plane(kG) + off, *eb = vp.plane(kB) + off;
      const float* tau = vp.plane(g.plane) + off;
      (g.squared ? cross_cells<true> : cross_cells<false>)(h, tau, er, eg, eb, ar, ag, ab, at);
    }
    TVal<S>* o = out + std::size_t(row) * h;
    for (int v = 0; v < h; ++v) put(o[v], Interval{ar[v], ag[v], ab[v], at[v]});
  });
}

// T_{n+1} from T_n: eq. 18 for even directions 2k, eqs. 19-20 for odd ones.
template <class S>
void merge_up(const View& view, int n, const TVal<S>* tn, TVal<S>* tn1) {
  const int P = view.probes(n), P1 = view.probes(n + 1), h = view.h;
  auto col = [&](int k, int x) -> const TVal<S>* {
    return x < P ? tn + (std::size_t(k) * P + x) * h : nullptr;
  };
  parallel_for(((1 << (n + 1)) + 1) * P1, [&](int row) {
    const int k2 = row / P1, x = row % P1;
    TVal<S>* o = tn1 + std::size_t(row) * h;
    if (k2 % 2 == 0) {
      const int k = k2 / 2, dy = vy(n, k);
      const TVal<S>*near = col(k, 2 * x), *far = col(k, 2 * x + 1);
      for_rows(h, {{far, dy}}, [&]<bool C>(int y) {
        put(o[y], merge_intervals(get_t<false>(near, y, h), get_t<C>(far, y + dy, h)));
      });
    } else {
      // Direction k + 1/2 is between two integer ones: average the two bent paths.
      const int k = k2 / 2, dy1 = vy(n, k + 1), dy0 = vy(n, k);
      const TVal<S>*a1 = col(k + 1, 2 * x), *b1 = col(k, 2 * x + 1);
      const TVal<S>*a0 = col(k, 2 * x), *b0 = col(k + 1, 2 * x + 1);
      for_rows(h, {{b1, dy1}, {b0, dy0}}, [&]<bool C>(int y) {
        const Interval p = merge_intervals(get_t<false>(a1, y, h), get_t<C>(b1, y + dy1, h));
        const Interval m = merge_intervals(get_t<false>(a0, y, h), get_t<C>(b0, y + dy0, h));
        put(o[y], Interval{0.5f * (p.r + m.r), 0.5f * (p.g + m.g), 0.5f * (p.b + m.b),
                           0.5f * (p.t + m.t)});
      });
    }
  });
}

// R_n from R_{n+1} (null at n + 1 = N: the environment), T_n and T_{n+1}.
template <class S>
void merge_down(const View& view, int n, const TVal<S>* tn, const TVal<S>* tn1, const RVal<S>* rn1,
                RVal<S>* rn, const Rgb& env) {
  const int P = view.probes(n), P1 = view.probes(n + 1), h = view.h;
  auto rcol = [&](int j, int x) -> const RVal<S>* {
    return rn1 && x < P1 ? rn1 + (std::size_t(j) * P1 + x) * h : nullptr;
  };
  parallel_for((1 << n) * P, [&](int row) {
    const int a = row / P, x = row % P;
    // The upper and lower halves of cone a are cones 2a + 1 and 2a of cascade n + 1.
    const float ap = cone_angle(n + 1, 2 * a + 1), am = cone_angle(n + 1, 2 * a);
    const Rad outp{env.r * ap, env.g * ap, env.b * ap}, outm{env.r * am, env.g * am, env.b * am};
    RVal<S>* o = rn + std::size_t(row) * h;
    if (x % 2 == 1) {
      // Eq. 14: trace each edge to the cascade-(n+1) probe it ends on, merge with its cone.
      const TVal<S>* tp = tn + (std::size_t(a + 1) * P + x) * h;
      const TVal<S>* tm = tn + (std::size_t(a) * P + x) * h;
      const int xq = (x + 1) / 2, dyp = vy(n, a + 1), dym = vy(n, a);
      const RVal<S>*rp = rcol(2 * a + 1, xq), *rm = rcol(2 * a, xq);
      for_rows(h, {{rp, dyp}, {rm, dym}}, [&]<bool C>(int y) {
        const Interval ep = get_t<false>(tp, y, h), em = get_t<false>(tm, y, h);
        const Rad fp = get_r<C>(rp, y + dyp, h, outp), fm = get_r<C>(rm, y + dym, h, outm);
        put(o[y], ap * ep.r + ep.t * fp.r + am * em.r + em.t * fm.r,
            ap * ep.g + ep.t * fp.g + am * em.g + em.t * fm.g,
            ap * ep.b + ep.t * fp.b + am * em.b + em.t * fm.b);
      });
    } else {
      // Eqs. 15-17: the mean of the cone at p itself and the merge along the doubled edge.
      const int xp = x / 2, xq = xp + 1;
      const int P1t = P1;  // T_{n+1} has the same probe columns as R_{n+1}
      const TVal<S>* up = tn1 + (std::size_t(2 * a + 2) * P1t + xp) * h;
      const TVal<S>* um = tn1 + (std::size_t(2 * a) * P1t + xp) * h;
      const RVal<S>*r0p = rcol(2 * a + 1, xp), *r0m = rcol(2 * a, xp);
      const int dyp = vy(n + 1, 2 * a + 2), dym = vy(n + 1, 2 * a);
      const RVal<S>*r1p = rcol(2 * a + 1, xq), *r1m = rcol(2 * a, xq);
      for_rows(h, {{r0p, 0}, {r0m, 0}, {r1p, dyp}, {r1m, dym}}, [&]<bool C>(int y) {
        const Interval ep = get_t<false>(up, y, h), em = get_t<false>(um, y, h);
        const Rad f0p = get_r<C>(r0p, y, h, outp), f0m = get_r<C>(r0m, y, h, outm);
        const Rad f1p = get_r<C>(r1p, y + dyp, h, outp), f1m = get_r<C>(r1m, y + dym, h, outm);
        put(o[y], 0.5f * (f0p.r + ap * ep.r + ep.t * f1p.r + f0m.r + am * em.r + em.t * f1m.r),
            0.5f * (f0p.g + ap * ep.g + ep.t * f1p.g + f0m.g + am * em.g + em.t * f1m.g),
            0.5f * (f0p.b + ap * ep.b + ep.t * f1p.b + f0m.b + am * em.b + em.t * f1m.b));
      });
    }
  });
}

// Trace([u, v], [u + 1, v]) from the centre of cell `own` into the centre of `next`, leaving an
// opaque own cell without interacting (as every method treats a wall cell's fluence: the light
// arriving at it).
inline Interval near_segment(const ViewPlanes& vp, std::size_t own) {
  const std::size_t next = own + vp.hp;
  const float* tau = vp.plane(kTau0);
  // An opaque own cell (e^-inf = 0) is left as if empty.
  const float t_own = tau[own] == 0.0f ? 1.0f : tau[own], t_next = tau[next];
  const float w_own = 1.0f - t_own, w_next = t_own * (1.0f - t_next);
  const float *r = vp.plane(kR), *g = vp.plane(kG), *b = vp.plane(kB);
  return {w_own * r[own] + w_next * r[next], w_own * g[own] + w_next * g[next],
          w_own * b[own] + w_next * b[next], t_own * t_next};
}

// Eq. 21: the 1-cell cross blur (4 at the centre, 1 at each side, over 8), leaving out
// neighbours whose opacity differs from the cell's by more than kBlurOpacityStep (and those
// beyond the grid), renormalised. Opacity over a cell length is 1 - tau(1/2)^2.
constexpr float kBlurOpacityStep = 0.5f;

void cross_blur(int W, int H, const float* tau_half, const float* f, float* out) {
  parallel_for(H, [&](int y) {
    for (int x = 0; x < W; ++x) {
      const std::size_t i = std::size_t(y) * W + x;
      const float op = 1.0f - tau_half[i] * tau_half[i];
      float r = 4 * f[3 * i], g = 4 * f[3 * i + 1], b = 4 * f[3 * i + 2], w = 4;
      auto add = [&](int nx, int ny) {
        if (nx < 0 || ny < 0 || nx >= W || ny >= H) return;
        const std::size_t j = std::size_t(ny) * W + nx;
        if (std::abs(1.0f - tau_half[j] * tau_half[j] - op) > kBlurOpacityStep) return;
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

template <class S>
void solve_with(const Medium& m, const Rgb& env, const HrcOptions& o, Buffers<S>& buf,
                Array<float>& planes, std::vector<float>& blurred, std::vector<float>& f,
                std::vector<StageTime>& stages) {
  const int W = m.width, H = m.height;
  const std::size_t cells = std::size_t(W) * H;
  const Sizes sz = plan(W, H);
  buf.t.resize(sz.t.size());
  std::vector<TVal<S>*> t(sz.t.size());
  for (std::size_t n = 0; n < t.size(); ++n) t[n] = buf.t[n].ensure(sz.t[n]);
  RVal<S>* r[2] = {buf.r[0].ensure(sz.r), buf.r[1].ensure(sz.r)};
  float* world = planes.ensure((cells + sz.pad) * kPlanes);
  ViewPlanes vp;
  vp.data = world + cells * kPlanes;
  vp.cells = sz.pad;
  std::vector<Segment> patterns[3][5];
  for (int n = 0; n < 3; ++n)
    for (int k = 0; k <= (1 << n); ++k) patterns[n][k] = ray_pattern(n, k);
  f.resize(cells * 3);

  Stopwatch watch;
  build_world(m, world);
  double ms_view = watch.ms(), ms_trace = 0, ms_up = 0, ms_down = 0;
  const float quarter = 1.57079633f;  // A_0: a quadrant, pi / 2
  for (int d = 0; d < 4; ++d) {
    const View& view = sz.views[d & 1];
    watch.restart();
    build_view(world, W, H, d, view, vp);
    ms_view += watch.ms();

    watch.restart();
    for (int n = 0; n <= std::min(2, view.levels); ++n) trace_level(view, n, vp, patterns[n], t[n]);
    ms_trace += watch.ms();
    watch.restart();
    for (int n = 3; n <= view.levels; ++n) merge_up(view, n - 1, t[n - 1], t[n]);
    ms_up += watch.ms();

    watch.restart();
    const RVal<S>* upper = nullptr;  // R_N: the environment
    for (int n = view.levels - 1; n >= 0; --n) {
      RVal<S>* out = upper == r[0] ? r[1] : r[0];
      merge_down(view, n, t[n], t[n + 1], upper, out, env);
      upper = out;
    }
    ms_down += watch.ms();

    // The quadrant's fluence at [u, v] is R_0([u + 1, v]): the offset keeps the diagonal rays
    // of neighbouring quadrants apart (seed 004, Fig. 12). With the near segment, the transport
    // from the cell's centre to that probe comes first, so a cell's own medium counts.
    watch.restart();
    const RVal<S>* r0 = upper;
    const Rad edge{env.r * quarter, env.g * quarter, env.b * quarter};
    const Rotation rot = rotation(d, W, H);
    for_view_cells(rot, view.w, view.h, [&](int u, int v) {
      Rad q =
          u + 1 < view.w ? get_r<false>(r0 + std::size_t(u + 1) * view.h, v, view.h, edge) : edge;
      if (o.near_segment) {
        const Interval n = near_segment(vp, vp.at(u, v));
        q = {quarter * n.r + n.t * q.r, quarter * n.g + n.t * q.g, quarter * n.b + n.t * q.b};
      }
      float* out = &f[std::size_t(rot.at(u, v)) * 3];
      if (d == 0)
        out[0] = q.r, out[1] = q.g, out[2] = q.b;
      else
        out[0] += q.r, out[1] += q.g, out[2] += q.b;
    });
    ms_view += watch.ms();
  }
  stages.push_back({"views", ms_view});
  stages.push_back({"trace T0-T2", ms_trace});
  stages.push_back({"merge up T3-TN", ms_up});
  stages.push_back({"merge down R", ms_down});
  if (o.cross_blur) {
    watch.restart();
    blurred.resize(cells * 3);
    cross_blur(W, H, world + kTau0 * cells, f.data(), blurred.data());
    std::swap(f, blurred);
    stages.push_back({"cross blur", watch.ms()});
  }
}

}  // namespace

int level_count(int w) {
  int n = 0;
  while ((std::int64_t(1) << n) < w) ++n;
  return n;
}

std::uint64_t working_bytes(int width, int height, const HrcOptions& o) {
  const Sizes s = plan(width, height);
  return o.storage == Storage::f16 ? bytes_of<Half>(s, width, height, o.cross_blur)
                                   : bytes_of<float>(s, width, height, o.cross_blur);
}

std::uint64_t structure_bytes(int width, int height, Storage storage) {
  const Sizes s = plan(width, height);
  const std::uint64_t vt = storage == Storage::f16 ? sizeof(TVal<Half>) : sizeof(TVal<float>);
  const std::uint64_t vr = storage == Storage::f16 ? sizeof(RVal<Half>) : sizeof(RVal<float>);
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
  Array<float> planes;
  std::vector<float> blurred;
};

Workspace::Workspace() : impl_(std::make_unique<Impl>()) {}
Workspace::~Workspace() = default;
Workspace::Workspace(Workspace&&) noexcept = default;
Workspace& Workspace::operator=(Workspace&&) noexcept = default;

void solve(const Medium& medium, const Rgb& environment, const HrcOptions& options,
           Workspace& workspace, std::vector<float>& fluence, std::vector<StageTime>& stages) {
  Workspace::Impl& w = *workspace.impl_;
  if (options.storage == Storage::f16) {
    w.f32.release();
    solve_with(medium, environment, options, w.f16, w.planes, w.blurred, fluence, stages);
  } else {
    w.f16.release();
    solve_with(medium, environment, options, w.f32, w.planes, w.blurred, fluence, stages);
  }
}

}  // namespace penumbra::hrc
