// Holographic radiance cascades on the CPU (seed 004, section 4).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/math.hpp"
#include "flatland/medium.hpp"
#include "penumbra/flatland/render.hpp"

namespace penumbra::flatland::hrc {

// Number of cascades N = ceil(log2(w)) for a view w cells long in the gathering direction.
int level_count(int w);

// Bytes HRC keeps alive: the acceleration structure T_0..T_N, two layers of R, the medium as
// planes (world layout and one rotated view) and the summed fluence, with the blur's copy (the
// largest of the two view orientations when the grid is not square), and a bound on the fan's.
std::uint64_t working_bytes(int width, int height, const HrcOptions& options);

// Bytes of the acceleration structure T_0..T_N and the two layers of R alone. For a 2^N x 2^N
// grid that is (N + 3 - 2^-N) 4^N (Vr + Vt) + 2 4^N Vr: the sum over n of 4^N (1 + 2^-n) for T
// (the seed prints + 2^-N, which the sum does not give).
std::uint64_t structure_bytes(int width, int height, Storage storage);

// The paper's count for a 2^N x 2^N grid (section 4.3.2) at the grid's larger side rounded up to
// a power of two: T = (N + 3 + 2^-N) 4^N (Vr + Vt) plus two layers of R, 2 4^N Vr.
std::uint64_t paper_bytes(int width, int height, const HrcOptions& options);

// Intervals traced through the cells (T_0..T_2 of the four quadrants); everything else is merged.
std::uint64_t traced_intervals(int width, int height);

// Largest radiance half-precision storage holds without overflowing (the angular fluence of a
// quadrant is at most pi/2 times the brightest radiance). The dispatcher renders brighter scenes
// at a power-of-two fraction of their light (render.cpp).
inline constexpr float kHalfMaxRadiance = 65504.0f / float(kPi / 2);

// The buffers of a solve, kept from one solve to the next of the same grid (bounces, the
// benchmarks, interactive use), so that the steady state allocates nothing. Buffers are not
// initialised when allocated: every kernel writes each element before it is read.
class Workspace {
 public:
  Workspace();
  ~Workspace();
  Workspace(Workspace&&) noexcept;
  Workspace& operator=(Workspace&&) noexcept;
  struct Impl;

 private:
  friend void solve(const Medium&, const Rgb&, const HrcOptions&, Workspace&, std::vector<float>&,
                    std::vector<StageTime>&, const float*);
  std::unique_ptr<Impl> impl_;
};

// Fluence at every cell centre into `fluence` (3 floats per cell, resized): the four quadrants
// on rotated views, summed, then the cross blur when enabled. Stage times are appended to
// `stages`. `lights` (3 per cell) is the scene's own emission, whose rims the near fan follows
// (a later bounce's medium also emits the light its walls reflect); null: the medium's.
void solve(const Medium& medium, const Rgb& environment, const HrcOptions& options,
           Workspace& workspace, std::vector<float>& fluence, std::vector<StageTime>& stages,
           const float* lights = nullptr);

// Eq. 21, the final 1-cell cross blur of the fluence f (3 floats per cell) into out, given the
// transmittance over half a cell per cell (0: opaque), rows tau_stride apart. Neighbours whose
// opacity differs by more than kBlurOpacityStep are left out; opaque cells neither blur nor are
// blurred into others.
inline constexpr float kBlurOpacityStep = 0.5f;
void cross_blur(int W, int H, const float* tau_half, int tau_stride, const float* f, float* out);

// Whether eq. 21 runs on the whole fluence, as a pass of its own after the quadrants (otherwise,
// when on, each quadrant's gather blurs the light from beyond the near segment).
inline bool blurs_whole_fluence(const HrcOptions& o) {
  return o.cross_blur && o.blur_near;
}
// Whether each quadrant's gather blurs its R_0 read (the light from beyond the near segment).
inline bool blurs_far_light(const HrcOptions& o) {
  return o.cross_blur && !o.blur_near;
}

// Whether eq. 21 mixes a non-opaque cell with a neighbour, given each one's transmittance over
// half a cell: not an opaque neighbour, nor one whose opacity differs by more than the step.
inline bool blur_together(float tau_cell, float tau_neighbour) {
  if (tau_neighbour == 0.0f) return false;
  const float a = 1.0f - tau_cell * tau_cell, b = 1.0f - tau_neighbour * tau_neighbour;
  return std::abs(a - b) <= kBlurOpacityStep;
}

// The near segment's part in a cell's own medium: the mean over a quadrant's directions of the
// transmittance from the cell's centre to its edge, (4 / pi) int_0^{pi/4} t^{1 / cos a} da,
// given the transmittance t over half a cell along an axis (4-point Gauss-Legendre, within 1e-6
// of the integral; the GPU's gather computes the same). A cell of fog or the anti-aliased rim of
// a light then gives its own light as every direction sees it, not only the axes.
float own_transmittance(float t);

// ---- The geometry of the solve, shared with the GPU backend (src/gpu/hrc.cpp) ----

// HrcOptions::fan_share: how many cells the fan gathers on a grid, the same on every scene:
// ceil(fan_share * cells), at least kMinFanCells (or every cell of a smaller grid); 0 when the
// solve runs no fan.
std::size_t fan_budget(int width, int height, const HrcOptions& options);
// The smallest grids' budget: the rim of a light 24 cells across and the cells within 2 of it
// (the disk of the tests, 128^2, needs about 330; 1/64 of its grid is 256).
inline constexpr std::size_t kMinFanCells = 512;
// The cells the fan gathers, fan_budget of them, as row-major world indices in order, ranked as
// HrcOptions::fan_share says: lit wall cells and lights' rims, then the cells that are not
// opaque by their distance along x and y to a rim (up to near_fan), then the other open cells,
// then the cells inside walls, within a rank in row order. A rim is a cell whose `lights` (3
// per cell; null: the medium's emission) are not all 0 with one among its 8 neighbours whose are.
// The scene overload reads its opacity (1: opaque) and its own emission: the GPU backend's cells,
// the same as the CPU's.
void fan_cells(const Medium& medium, const float* lights, const HrcOptions& options,
               std::vector<std::uint32_t>& cells);
void fan_cells(const Scene& scene, const HrcOptions& options, std::vector<std::uint32_t>& cells);
inline constexpr int kWallFanRays = 2;  // per cone

// Eq. 13: the angle of cone a (the paper's i = a + 1/2) of cascade n.
float cone_angle(int n, int a);

// One quadrant's rotated grid: w cells along the gathering direction (+u), h across.
struct View {
  int w = 0, h = 0;
  int levels = 0;                                                                 // N
  int probes(int n) const { return int((std::int64_t(w) + (1 << n) - 1) >> n); }  // P_n
  std::size_t t_size(int n) const { return std::size_t(probes(n)) * ((1 << n) + 1) * h; }
  std::size_t r_size(int n) const { return std::size_t(probes(n)) * (1 << n) * h; }
};
View make_view(int w, int h);
// The cascade HrcOptions::wall_fan reads on a view: the option, or the highest below the
// environment; -1: none.
inline int wall_fan_level(const View& v, int wall_fan) {
  return wall_fan > 0 ? (wall_fan < v.levels ? wall_fan : v.levels - 1) : -1;
}
// Whether a solve runs the fan: on, and every quadrant has a cascade for it (a grid one cell
// wide has none across).
inline bool runs_fan(int width, int height, const HrcOptions& o) {
  return o.wall_fan > 0 && width > 1 && height > 1;
}

// Rotated views carry this many empty cells beyond the grid (the longest traced ray, T_2's
// (4, +-4), ends 4 cells out), so the traced levels read them without bounds checks.
inline constexpr int kPad = 5;

// The rays of T_0..T_2 cross cells along 6 lengths: 1/2, sqrt5/4, sqrt2/2 and their doubles.
// A rotated view keeps, per cell, the emission and the transmittance over the three short
// ones (the doubles are their squares), so tracing is multiply-adds: no exp, no branch, the
// same work whatever the scene holds. Opaque cells have transmittance 0 (e^-inf).
inline constexpr float kLengths[3] = {0.5f, 0.559016994f, 0.707106781f};

// Everything a solve allocates, sized for both view orientations: working_bytes() and solve()
// agree by construction.
struct Sizes {
  View views[2];
  std::vector<std::size_t> t;  // elements of T_n, n = 0..N
  std::size_t r = 0;           // elements of one R layer
  std::size_t pad = 0;         // cells of the rotated medium
};
Sizes plan(int width, int height);

// Where view cell (u, v) of quadrant d = +x, +y, -x, -y lies in a row-major world array:
// base + u * su + v * sv. The rotation takes the quadrant's direction to +u (a rotation, not a
// mirror, so a rotated scene permutes the quadrants and nothing else).
struct Rotation {
  std::ptrdiff_t base, su, sv;
  std::ptrdiff_t at(int u, int v) const { return base + u * su + v * sv; }
};
// Rows of the world `stride` cells apart (0: `width`).
Rotation rotation(int d, int width, int height, std::ptrdiff_t stride = 0);
// rotation() for points, and its inverse: the world point (cell units, row 0 at the top) of
// view point (u, v), cell centres at integers; the view cell of world cell (x, y).
struct Point {
  float x, y;
};
Point world_point(int d, int width, int height, float u, float v);
void view_cell(int d, int width, int height, int x, int y, int& u, int& v);
// The row stride for n floats that keeps rows out of each other's L1 sets (the CPU solver's
// world planes).
int unaliased_stride(int n);

// The cells ray k of T_n crosses, in order, each with its length, and the corners a 45-degree
// ray passes through between two cells it does not enter: each of those cells that is opaque
// stops half of the ray (so walls meeting only at corners do not leak).
struct TracedCell {
  int du, dv;
  int length;      // index into kLengths
  bool squared;    // twice that length
  int corner = 0;  // +-1: not a cell but the corner of (du, dv) towards (du + 1, dv) and
                   // (du, dv + corner)
};
std::vector<TracedCell> traced_cells(int n, int k);

}  // namespace penumbra::flatland::hrc
