// Rasterising a SceneDesc into per-cell emission, opacity and albedo.
//
// Layers are copied first; shapes are then drawn in order with anti-aliased coverage. A cell is
// classified by the signed distance from its centre to the shape boundary: a cell lies within
// sqrt(2)/2 of its centre, so beyond that distance it is fully inside or outside, and only
// boundary cells are supersampled (16x16 points, exact inside tests). Polygons get the same
// classes and samples from a scanline fill (PolygonFill), in time proportional to their cells
// and edges rather than their product; disks count a row's samples by its inside run
// (RowSamples); the shapes between polygons are drawn by bands of rows (draw_run). Every cell's
// result is that of the plain per-cell, per-sample test. Cost laws: docs/scene-format.md.
#include "flatland/scene/rasterize.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <variant>
#include <vector>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "penumbra/flatland/scene.hpp"

namespace penumbra::flatland {
namespace {

constexpr double kHalfDiagonal = 0.70710678118654752440;
constexpr int kSamples = 16;  // per axis, in boundary cells

struct Bounds {
  double x0, y0, x1, y1;
};

double length(double x, double y) {
  return std::sqrt(x * x + y * y);
}

// Distance from p to the segment a-b.
double segment_distance(double px, double py, double ax, double ay, double bx, double by) {
  double dx = bx - ax, dy = by - ay;
  double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? std::clamp(((px - ax) * dx + (py - ay) * dy) / len2, 0.0, 1.0) : 0.0;
  return length(px - ax - t * dx, py - ay - t * dy);
}

// The x of sample s in cell i (or the y of sample row s in row j), as the inside tests have
// always used it.
double sample_coord(int i, int s) {
  return i + (s + 0.5) / kSamples;
}

// A ceiling of an estimate as an int in [lo, hi], for an estimate that may be far out or huge.
int clamped_ceil(double estimate, int lo, int hi) {
  return !(estimate > lo) ? lo : estimate >= hi ? hi : int(std::ceil(estimate));
}

// How many of the increasing positions pos(0..n-1) lie left of xc (pos(k) < xc), starting from
// an estimate that is off by a sample at most for any xc near the grid.
template <class Pos>
int count_left(double xc, double estimate, int n, const Pos& pos) {
  int k = clamped_ceil(estimate, 0, n);
  while (k > 0 && !(pos(k - 1) < xc)) --k;
  while (k < n && pos(k) < xc) ++k;
  return k;
}

// Each geometry: signed distance (negative inside), exact inside test, bounding box.
struct DiskGeom {
  double cx, cy, r;
  explicit DiskGeom(const Circle& c) : cx(c.center[0]), cy(c.center[1]), r(c.radius) {}
  double distance(double x, double y) const { return length(x - cx, y - cy) - r; }
  bool inside(double x, double y) const {
    double dx = x - cx, dy = y - cy;
    return dx * dx + dy * dy < r * r;
  }
  Bounds bounds() const { return {cx - r, cy - r, cx + r, cy + r}; }
};

struct BoxGeom {
  double cx, cy, hw, hh, cs, sn;
  explicit BoxGeom(const Box& b)
      : cx(b.center[0]), cy(b.center[1]), hw(b.size[0] / 2.0), hh(b.size[1] / 2.0) {
    // The box's local x axis is (cos, sin) in y-down coordinates: +x turning towards +y.
    double a = double(b.angle) * (kPi / 180.0);
    cs = std::cos(a);
    sn = std::sin(a);
  }
  void local(double x, double y, double& u, double& v) const {
    double dx = x - cx, dy = y - cy;
    u = dx * cs + dy * sn;
    v = -dx * sn + dy * cs;
  }
  double distance(double x, double y) const {
    double u, v;
    local(x, y, u, v);
    double qx = std::fabs(u) - hw, qy = std::fabs(v) - hh;
    return length(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0);
  }
  bool inside(double x, double y) const {
    double u, v;
    local(x, y, u, v);
    return std::fabs(u) < hw && std::fabs(v) < hh;
  }
  Bounds bounds() const {
    double ex = std::fabs(cs) * hw + std::fabs(sn) * hh;
    double ey = std::fabs(sn) * hw + std::fabs(cs) * hh;
    return {cx - ex, cy - ey, cx + ex, cy + ey};
  }
};

struct CapsuleGeom {
  double ax, ay, bx, by, r;
  explicit CapsuleGeom(const Segment& s)
      : ax(s.a[0]), ay(s.a[1]), bx(s.b[0]), by(s.b[1]), r(s.width / 2.0) {}
  double distance(double x, double y) const { return segment_distance(x, y, ax, ay, bx, by) - r; }
  bool inside(double x, double y) const { return segment_distance(x, y, ax, ay, bx, by) < r; }
  Bounds bounds() const {
    return {std::min(ax, bx) - r, std::min(ay, by) - r, std::max(ax, bx) + r, std::max(ay, by) + r};
  }
};

// The first k in [lo, hi) with pred(k), or hi, for pred false then true on [lo, hi); stepping from
// `guess`, so a good guess costs one or two tests.
template <class Pred>
int first_true(int lo, int hi, int guess, const Pred& pred) {
  int k = std::clamp(guess, lo, hi);
  if (k < hi && !pred(k)) {
    do ++k;
    while (k < hi && !pred(k));
    return k;
  }
  while (k > lo && pred(k - 1)) --k;
  return k;
}

// Counts the inside samples of edge cells in row j of a shape's cells [i0, i1): each of a
// cell's 16x16 samples is tested.
template <class Geom>
class RowSamples {
 public:
  RowSamples(const Geom& g, int /*i0*/, int /*i1*/, int j) : g_(g), j_(j) {}
  int hits(int i) {
    int n = 0;
    for (int sy = 0; sy < kSamples; ++sy) {
      const double y = sample_coord(j_, sy);
      for (int sx = 0; sx < kSamples; ++sx) n += g_.inside(sample_coord(i, sx), y);
    }
    return n;
  }

 private:
  const Geom& g_;
  int j_;
};

// A disk's inside samples on a row of samples are one run: rounding is monotone, so dx * dx
// grows with |x - cx| on either side of cx. The runs of the row's 16 sample rows are found once,
// by searching their ends from the exact circle's, and a cell's hits are its overlap with them:
// the same count as testing each sample, at a fraction of the tests.
template <>
class RowSamples<DiskGeom> {
 public:
  RowSamples(const DiskGeom& g, int i0, int i1, int j) : g_(g), i0_(i0), i1_(i1), j_(j) {}
  int hits(int i) {
    if (!found_) find_runs();
    const int lo = (i - i0_) * kSamples, hi = lo + kSamples;
    int n = 0;
    for (int sy = 0; sy < kSamples; ++sy)
      n += std::max(0, std::min(b_[sy], hi) - std::max(a_[sy], lo));
    return n;
  }

 private:
  void find_runs() {
    found_ = true;
    const int n = (i1_ - i0_) * kSamples;
    const auto x = [&](int k) { return sample_coord(i0_ + k / kSamples, k % kSamples); };
    const auto guess = [&](double edge) {
      return clamped_ceil((edge - i0_) * kSamples - 0.5, 0, n);
    };
    // Samples [0, m) lie left of the centre: there the run can only start.
    const int m = count_left(g_.cx, guess(g_.cx), n, x);
    for (int sy = 0; sy < kSamples; ++sy) {
      const double y = sample_coord(j_, sy), dy = y - g_.cy, s2 = g_.r * g_.r - dy * dy;
      const double half = s2 > 0 ? std::sqrt(s2) : 0;
      const auto in = [&](int k) { return g_.inside(x(k), y); };
      a_[sy] = first_true(0, m, guess(g_.cx - half), in);
      b_[sy] = first_true(m, n, guess(g_.cx + half), [&](int k) { return !in(k); });
    }
  }

  const DiskGeom& g_;
  int i0_, i1_, j_;
  bool found_ = false;
  int a_[kSamples], b_[kSamples];  // sample row sy's inside samples: [a_, b_) from i0's first
};

// Fraction of cell (i, j) covered by the shape; `row` counts samples in row j.
template <class Geom>
float coverage(const Geom& g, int i, int j, RowSamples<Geom>& row) {
  double d = g.distance(i + 0.5, j + 0.5);
  if (d <= -kHalfDiagonal) return 1;
  if (d >= kHalfDiagonal) return 0;
  return float(row.hits(i)) / float(kSamples * kSamples);
}

}  // namespace

// A ray grazing the edge of an opaque shape crosses several partly covered cells in a row and
// their opacities compound, so blending opaque coverage linearly makes a disk look up to half a
// cell wider than it is. Sharpening the coverage to c^4 keeps the silhouette of disks of radius 4
// to 30 within 0.16 cells of the true one (measured; see docs/scene-format.md). Materials that
// are not opaque blend linearly, which keeps their optical depth on average.
float opaque_edge(float c) {
  const float c2 = c * c;
  return c2 * c2;
}

// Premultiplied "over": the shape replaces the old values in the covered fraction c, with
// emission and albedo weighted by opacity so that a partly covered emitter cell emits like its
// covered part. c == 1 copies the material exactly.
void blend(Scene& s, std::size_t idx, float c, const Material& m) {
  float* le = &s.emission[idx * 3];
  float* rho = &s.albedo[idx * 3];
  const float le1[3] = {m.emission.r, m.emission.g, m.emission.b};
  const float rho1[3] = {m.albedo.r, m.albedo.g, m.albedo.b};
  if (c >= 1) {
    s.opacity[idx] = m.opacity;
    for (int k = 0; k < 3; ++k) {
      le[k] = le1[k];
      rho[k] = rho1[k];
    }
    return;
  }
  const float w1 = c * m.opacity, w0 = (1 - c) * s.opacity[idx];
  const float a = w1 + w0;
  s.opacity[idx] = a;
  for (int k = 0; k < 3; ++k) {
    le[k] = a > 0 ? (w1 * le1[k] + w0 * le[k]) / a : 0.0f;
    rho[k] = a > 0 ? (w1 * rho1[k] + w0 * rho[k]) / a : 0.0f;
  }
}

namespace {

// Cell index range [lo, hi) touched by the interval [a, b], clipped to [0, n).
void cell_range(double a, double b, int n, int& lo, int& hi) {
  lo = int(std::clamp(std::floor(a), 0.0, double(n)));
  hi = int(std::clamp(std::ceil(b), 0.0, double(n)));
}

// A shape's cells [i0, i1) x [j0, j1): its bounding box clipped to the grid.
struct CellBox {
  int i0, i1, j0, j1;
  bool empty() const { return i0 >= i1 || j0 >= j1; }
};

CellBox cell_box(const Bounds& b, int width, int height) {
  CellBox c;
  cell_range(b.x0, b.x1, width, c.i0, c.i1);
  cell_range(b.y0, b.y1, height, c.j0, c.j1);
  return c;
}

// Calls f with the geometry of a circle, box or segment.
template <class F>
void with_geom(const Shape& shape, const F& f) {
  std::visit(
      [&](const auto& geom) {
        using T = std::decay_t<decltype(geom)>;
        if constexpr (std::is_same_v<T, Circle>) {
          f(DiskGeom(geom));
        } else if constexpr (std::is_same_v<T, Box>) {
          f(BoxGeom(geom));
        } else if constexpr (std::is_same_v<T, Segment>) {
          f(CapsuleGeom(geom));
        }
      },
      shape.geometry);
}

// Draws rows [ja, jb) of a shape whose cells are `box`.
template <class Geom>
void draw_rows(Scene& s, const Geom& g, const Material& m, const CellBox& box, int ja, int jb) {
  for (int j = ja; j < jb; ++j) {
    RowSamples<Geom> row(g, box.i0, box.i1, j);
    for (int i = box.i0; i < box.i1; ++i) {
      const float c = coverage(g, i, j, row);
      if (c > 0) blend(s, s.index(i, j), blend_fraction(c, m), m);
    }
  }
}

constexpr int kBandRows = 8;

// Draws shapes [first, last), none a polygon. The grid's rows are split into bands drawn in
// parallel, each drawing its rows of every shape that reaches it, in scene order: a cell still
// takes its shapes in order and is computed alone, so results do not depend on threads, and a
// small shape costs no parallel dispatch of its own (scenes of many small shapes used to).
void draw_run(Scene& s, const std::vector<Shape>& shapes, std::size_t first, std::size_t last) {
  const int bands = (s.height + kBandRows - 1) / kBandRows;
  std::vector<CellBox> boxes(last - first);
  // The shapes reaching each band, in order: items[start[b] .. start[b + 1]).
  std::vector<std::size_t> start(bands + 1, 0);
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    with_geom(shapes[first + k],
              [&](const auto& g) { boxes[k] = cell_box(g.bounds(), s.width, s.height); });
    if (boxes[k].empty()) continue;
    for (int b = boxes[k].j0 / kBandRows; b <= (boxes[k].j1 - 1) / kBandRows; ++b) ++start[b + 1];
  }
  for (int b = 0; b < bands; ++b) start[b + 1] += start[b];
  std::vector<std::size_t> items(start[bands]), fill(start.begin(), start.end() - 1);
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    if (boxes[k].empty()) continue;
    for (int b = boxes[k].j0 / kBandRows; b <= (boxes[k].j1 - 1) / kBandRows; ++b)
      items[fill[b]++] = k;
  }
  parallel_for(bands, [&](int b) {
    for (std::size_t t = start[b]; t < start[b + 1]; ++t) {
      const std::size_t k = items[t];
      const CellBox& box = boxes[k];
      const Shape& shape = shapes[first + k];
      const int ja = std::max(box.j0, b * kBandRows), jb = std::min(box.j1, (b + 1) * kBandRows);
      with_geom(shape, [&](const auto& g) { draw_rows(s, g, shape.material, box, ja, jb); });
    }
  });
}

// Polygons: a scanline fill, in time proportional to the cells drawn plus edges times the rows
// they span (the brute-force test of every cell against every edge cost cells x edges).
//
// Each cell's class and each sample's inside decision are those of the brute-force test. A cell
// is an edge cell iff some edge lies within sqrt(2)/2 of its centre: per row, each edge near the
// row lists the cells it may reach (a conservative x-range) and only those are measured, with the
// same segment_distance. Inside tests become crossings: the even-odd test counts edges whose
// crossing x on the sample's row, by the same expression, lies right of the sample, so a crossing
// flips every sample left of it; a toggle at its position and a XOR sweep from the right give
// each sample's parity without sorting.
struct PolyEdge {
  double xi, yi, xj, yj;  // a point and the one before it, as the even-odd test names them
  double margin;          // for rounding in the candidate ranges, far above it
  int r0, r1;             // rows [r0, r1] it may cross or come within sqrt(2)/2 of
};

bool crosses(const PolyEdge& e, double y) {
  return (e.yi > y) != (e.yj > y);
}

// Where the edge meets row y; `x < crossing_x` is the even-odd test's comparison.
double crossing_x(const PolyEdge& e, double y) {
  return e.xj + (y - e.yj) * (e.xi - e.xj) / (e.yi - e.yj);
}

class PolygonFill {
 public:
  // Cells [i0, i1) x [j0, j1), the polygon's bounding box clipped to the grid.
  PolygonFill(const Polygon& p, int i0, int i1, int j0, int j1)
      : i0_(i0), i1_(i1), j0_(j0), j1_(j1) {
    const auto& pts = p.points;
    const std::size_t n = pts.size();
    edges_.reserve(n);
    for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
      PolyEdge e{pts[i][0], pts[i][1], pts[j][0], pts[j][1], 0, 0, 0};
      // Rounding in the ranges below and in segment_distance is ~1e-15 of these magnitudes.
      e.margin = 1e-9 * (1 + std::fabs(e.xi) + std::fabs(e.yi) + std::fabs(e.xj) + std::fabs(e.yj) +
                         i1 + j1);
      // Rows whose centre is within sqrt(2)/2 of the edge's y-extent; they include the rows it
      // crosses, as a row's samples lie within 1/2 of its centre.
      const double lo = std::ceil(std::min(e.yi, e.yj) - kHalfDiagonal - e.margin - 0.5);
      const double hi = std::floor(std::max(e.yi, e.yj) + kHalfDiagonal + e.margin - 0.5);
      if (hi < j0 || lo > j1 - 1) continue;
      e.r0 = int(std::max(lo, double(j0)));
      e.r1 = int(std::min(hi, double(j1 - 1)));
      edges_.push_back(e);
    }
  }

  // Rows are filled in bands; the split depends on the box alone, never on threads.
  int bands() const { return (rows() + band_rows() - 1) / band_rows(); }

  // Calls emit(i, j, coverage) for each cell of band b with coverage > 0.
  template <class Emit>
  void fill_band(int b, PolygonWork& work, const Emit& emit) const {
    const int ja = j0_ + b * band_rows(), jb = std::min(j1_, ja + band_rows());
    std::vector<int> order;  // this band's edges, by first row
    for (int k = 0; k < int(edges_.size()); ++k)
      if (edges_[k].r1 >= ja && edges_[k].r0 < jb) order.push_back(k);
    work.edge_visits += edges_.size();
    std::sort(order.begin(), order.end(),
              [&](int a, int c) { return edges_[a].r0 < edges_[c].r0; });

    const int w = i1_ - i0_;
    std::vector<PolyEdge> active;  // the edges of row j, copied so that the 17 passes over them
                                   // read memory in order
    std::vector<unsigned char> edge_cell(w), centre_in(w), flip(w + 1);
    std::vector<std::uint16_t> partial(w);
    std::vector<int> hits(w);
    std::size_t next = 0;
    for (int j = ja; j < jb; ++j) {
      while (next < order.size() && edges_[order[next]].r0 <= j)
        active.push_back(edges_[order[next++]]);
      std::erase_if(active, [&](const PolyEdge& e) { return e.r1 < j; });
      work.edge_visits += active.size();

      const bool any_edge_cell = mark_edge_cells(j, active, edge_cell, work);
      centre_parity(j, active, flip, centre_in, work);
      if (any_edge_cell) count_hits(j, active, edge_cell, flip, partial, hits, work);
      for (int c = 0; c < w; ++c) {
        const float cov =
            edge_cell[c] ? float(hits[c]) / float(kSamples * kSamples) : float(centre_in[c]);
        if (cov > 0) emit(i0_ + c, j, cov);
      }
    }
  }

 private:
  int rows() const { return j1_ - j0_; }
  // At least 4 rows a band so that most edges are gathered once, and at most 32 bands.
  int band_rows() const { return std::max(4, (rows() + 31) / 32); }

  // Marks the cells of row j whose centre is within sqrt(2)/2 of an edge; true if any.
  bool mark_edge_cells(int j, const std::vector<PolyEdge>& active,
                       std::vector<unsigned char>& edge_cell, PolygonWork& work) const {
    std::fill(edge_cell.begin(), edge_cell.end(), 0);
    bool any = false;
    const double yc = j + 0.5;
    for (const PolyEdge& e : active) {
      // The part of the edge within sqrt(2)/2 of the row's centre line, as an x-range.
      const double reach = kHalfDiagonal + e.margin;
      const double ylo = std::min(e.yi, e.yj), yhi = std::max(e.yi, e.yj);
      if (yc < ylo - reach || yc > yhi + reach) continue;
      double xa = std::min(e.xi, e.xj), xb = std::max(e.xi, e.xj);
      if (e.yi != e.yj) {
        const double ta = (yc - reach - e.yj) / (e.yi - e.yj);
        const double tb = (yc + reach - e.yj) / (e.yi - e.yj);
        const double t0 = std::clamp(std::min(ta, tb), 0.0, 1.0);
        const double t1 = std::clamp(std::max(ta, tb), 0.0, 1.0);
        const double x0 = e.xj + t0 * (e.xi - e.xj), x1 = e.xj + t1 * (e.xi - e.xj);
        xa = std::min(x0, x1);
        xb = std::max(x0, x1);
      }
      // Cells whose centre i + 0.5 lies within `reach` of [xa, xb].
      const double ca = std::ceil(xa - reach - 0.5), cb = std::floor(xb + reach - 0.5);
      if (cb < i0_ || ca > i1_ - 1) continue;
      const int ia = int(std::max(ca, double(i0_))), ib = int(std::min(cb, double(i1_ - 1)));
      work.distance_tests += ib - ia + 1;
      for (int i = ia; i <= ib; ++i) {
        if (segment_distance(i + 0.5, yc, e.xj, e.yj, e.xi, e.yi) < kHalfDiagonal) {
          edge_cell[i - i0_] = 1;
          any = true;
        }
      }
    }
    return any;
  }

  // centre_in[c]: whether the centre of cell i0 + c of row j is inside.
  void centre_parity(int j, const std::vector<PolyEdge>& active, std::vector<unsigned char>& flip,
                     std::vector<unsigned char>& centre_in, PolygonWork& work) const {
    const int w = i1_ - i0_;
    const double y = j + 0.5;
    std::fill(flip.begin(), flip.end(), 0);
    const auto centre = [&](int c) { return i0_ + c + 0.5; };
    for (const PolyEdge& e : active) {
      if (!crosses(e, y)) continue;
      const double xc = crossing_x(e, y);
      flip[count_left(xc, xc - i0_ - 0.5, w, centre)] ^= 1;
    }
    work.crossing_tests += active.size();
    work.cell_visits += w;
    unsigned char in = 0;
    for (int c = w - 1; c >= 0; --c) centre_in[c] = in ^= flip[c + 1];
  }

  // hits[c]: how many of the 16x16 samples of edge cell i0 + c of row j are inside.
  void count_hits(int j, const std::vector<PolyEdge>& active,
                  const std::vector<unsigned char>& edge_cell, std::vector<unsigned char>& flip,
                  std::vector<std::uint16_t>& partial, std::vector<int>& hits,
                  PolygonWork& work) const {
    const int w = i1_ - i0_, n = w * kSamples;
    std::fill(hits.begin(), hits.end(), 0);
    const auto sample = [&](int k) { return sample_coord(i0_ + k / kSamples, k % kSamples); };
    for (int sy = 0; sy < kSamples; ++sy) {
      const double y = sample_coord(j, sy);
      // A crossing left of sample k = kSamples * q + s flips the cells before q and the
      // samples before s in cell q.
      std::fill(flip.begin(), flip.end(), 0);
      std::fill(partial.begin(), partial.end(), 0);
      for (const PolyEdge& e : active) {
        if (!crosses(e, y)) continue;
        const double xc = crossing_x(e, y);
        const int left = count_left(xc, (xc - i0_) * kSamples - 0.5, n, sample);
        const int q = left / kSamples, s = left % kSamples;
        flip[q] ^= 1;
        if (s > 0) partial[q] ^= std::uint16_t((1u << s) - 1);
      }
      work.crossing_tests += active.size();
      work.cell_visits += w;
      unsigned char in = 0;
      for (int c = w - 1; c >= 0; --c) {
        in ^= flip[c + 1];
        if (!edge_cell[c]) continue;
        const unsigned mask = (in ? 0xFFFFu : 0u) ^ partial[c];
        hits[c] += std::popcount(mask);
      }
    }
  }

  int i0_, i1_, j0_, j1_;
  std::vector<PolyEdge> edges_;
};

Bounds polygon_bounds(const Polygon& p) {
  const auto& pts = p.points;
  Bounds b{pts[0][0], pts[0][1], pts[0][0], pts[0][1]};
  for (const auto& q : pts) {
    b.x0 = std::min(b.x0, double(q[0]));
    b.y0 = std::min(b.y0, double(q[1]));
    b.x1 = std::max(b.x1, double(q[0]));
    b.y1 = std::max(b.y1, double(q[1]));
  }
  return b;
}

// Calls emit(i, j, coverage) for each cell of a width x height grid the polygon covers, rows in
// parallel for large polygons; adds the work done to *work when given.
template <class Emit>
void fill_polygon(const Polygon& p, int width, int height, PolygonWork* work, const Emit& emit) {
  const Bounds b = polygon_bounds(p);
  int i0, i1, j0, j1;
  cell_range(b.x0, b.x1, width, i0, i1);
  cell_range(b.y0, b.y1, height, j0, j1);
  if (i0 >= i1 || j0 >= j1) return;
  const PolygonFill fill(p, i0, i1, j0, j1);
  std::vector<PolygonWork> band_work(fill.bands());
  // A small polygon is filled on this thread: a parallel dispatch would cost more.
  const auto band = [&](int k) { fill.fill_band(k, band_work[k], emit); };
  if (long(i1 - i0) * (j1 - j0) + long(p.points.size()) < 4096) {
    for (int k = 0; k < fill.bands(); ++k) band(k);
  } else {
    parallel_for(fill.bands(), band);
  }
  if (!work) return;
  for (const PolygonWork& w : band_work) {
    work->edge_visits += w.edge_visits;
    work->crossing_tests += w.crossing_tests;
    work->distance_tests += w.distance_tests;
    work->cell_visits += w.cell_visits;
  }
}

}  // namespace

namespace {

Expected<Scene> build_scene_unchecked(const SceneDesc& desc) {
  if (Status st = validate(desc); !st) return st.error();

  Scene s;
  s.width = desc.width;
  s.height = desc.height;
  s.environment = desc.environment;
  const std::size_t n = s.cells();
  s.emission.assign(n * 3, 0.0f);
  s.albedo.assign(n * 3, 0.0f);
  s.opacity.assign(n, 0.0f);

  const Layers& layers = desc.layers;
  if (layers.emission) std::copy_n(layers.emission->data(), n * 3, s.emission.begin());
  if (layers.albedo) std::copy_n(layers.albedo->data(), n * 3, s.albedo.begin());
  if (layers.opacity) {
    std::copy_n(layers.opacity->data(), n, s.opacity.begin());
  } else {
    // Without an opacity layer, painted emitters are opaque and everything else is empty:
    // under the transport rule a cell of opacity 0 emits nothing, so an emission layer alone
    // would otherwise be invisible.
    for (std::size_t i = 0; i < n; ++i) {
      const float* e = &s.emission[i * 3];
      s.opacity[i] = (e[0] != 0 || e[1] != 0 || e[2] != 0) ? 1.0f : 0.0f;
    }
  }

  // Polygons one by one, the shapes between them in runs.
  const std::vector<Shape>& shapes = desc.shapes;
  for (std::size_t k = 0; k < shapes.size();) {
    if (const auto* p = std::get_if<Polygon>(&shapes[k].geometry)) {
      const Material& m = shapes[k].material;
      fill_polygon(*p, s.width, s.height, nullptr, [&](int i, int j, float c) {
        blend(s, s.index(i, j), blend_fraction(c, m), m);
      });
      ++k;
      continue;
    }
    std::size_t last = k + 1;
    while (last < shapes.size() && !std::holds_alternative<Polygon>(shapes[last].geometry)) ++last;
    draw_run(s, shapes, k, last);
    k = last;
  }
  return s;
}

}  // namespace

std::vector<float> polygon_coverage(const Polygon& p, int width, int height, PolygonWork* work) {
  std::vector<float> cov(std::size_t(width) * height, 0.0f);
  fill_polygon(p, width, height, work,
               [&](int i, int j, float c) { cov[std::size_t(j) * width + i] = c; });
  return cov;
}

Expected<Scene> build_scene(const SceneDesc& desc) {
  try {
    return build_scene_unchecked(desc);
  } catch (const std::bad_alloc&) {
    return Error{desc.source + ": out of memory while rasterising the scene"};
  } catch (const std::exception& e) {
    return Error{desc.source + ": " + e.what()};
  }
}

}  // namespace penumbra::flatland
