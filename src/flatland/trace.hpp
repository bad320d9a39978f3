// Tracing a ray interval through the cell grid: exact cell traversal (Amanatides-Woo DDA) that
// integrates each cell's transport analytically, with two ways to skip empty space: 8x8 blocks
// that hold nothing (a two-level DDA) and sphere-tracing jumps where the medium has a distance
// field. Both only skip cells that contribute nothing and land on the parameters the plain DDA
// computes, so every combination gives the same bits; the DDA is the ground truth.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "flatland/interval.hpp"
#include "flatland/medium.hpp"

namespace penumbra::flatland {

namespace detail {

// Clips [ta, tb] to the grid box [0, w] x [0, h]. Returns false when nothing is left.
inline bool clip_to_grid(float ox, float oy, float dx, float dy, float w, float h, float& ta,
                         float& tb) {
  auto slab = [&](float o, float d, float hi) {
    if (d == 0.0f) return o >= 0.0f && o <= hi;
    float t0 = (0.0f - o) / d, t1 = (hi - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    ta = std::max(ta, t0);
    tb = std::min(tb, t1);
    return true;
  };
  if (!slab(ox, dx, w) || !slab(oy, dy, h)) return false;
  return ta < tb;
}

}  // namespace detail

// Calls visit(cell index, step, t_enter, t_exit) for every interacting cell (Medium::step > 0)
// the interval o + t*d, t in [ta, tb], passes through, in order, until visit returns false.
// With skip_start, an opaque cell the interval starts strictly inside is not visited (a ray
// starting on a cell boundary enters the cell it moves into).
// Always inlined, so the visitor's state stays in registers; callers are few (trace_interval,
// the path tracer's scattering walk).
template <class Visit>
[[gnu::always_inline]] inline void walk_cells(const Medium& m, float ox, float oy, float dx,
                                              float dy, float ta, float tb, bool skip_start,
                                              Visit&& visit) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  // Fast exit: an interval that starts in an empty cell and ends within the jump allowed from
  // there meets nothing (most short intervals away from walls).
  {
    const float px = ox + dx * ta, py = oy + dy * ta;
    if (px >= 0.0f && py >= 0.0f && px < float(m.width) && py < float(m.height)) {
      const float step = m.step[std::size_t(py) * m.width + std::size_t(px)];
      if (step < 0.0f && tb - ta <= -step) return;
    }
  }
  float t = ta, tend = tb;
  if (!detail::clip_to_grid(ox, oy, dx, dy, float(m.width), float(m.height), t, tend)) return;
  const int step_x = dx > 0 ? 1 : -1, step_y = dy > 0 ? 1 : -1;
  // Cell exits are always computed from the origin with the same formula (never accumulated),
  // so a ray that skipped ahead meets every later cell boundary at exactly the same parameter.
  const float inv_x = dx != 0 ? 1.0f / dx : 0.0f, inv_y = dy != 0 ? 1.0f / dy : 0.0f;
  auto exit_x = [&](int cx) { return dx != 0 ? (float(cx + (dx > 0)) - ox) * inv_x : kInf; };
  auto exit_y = [&](int cy) { return dy != 0 ? (float(cy + (dy > 0)) - oy) * inv_y : kInf; };

  int ix = 0, iy = 0;
  float tmax_x = kInf, tmax_y = kInf;
  // Locates the cell holding the point at parameter tt (the start, or where a distance-field
  // jump lands: inside empty space, so either cell of a boundary is right).
  auto locate = [&](float tt) {
    const float px = ox + dx * tt, py = oy + dy * tt;
    ix = int(std::floor(px));
    iy = int(std::floor(py));
    if (dx < 0 && float(ix) == px) --ix;
    if (dy < 0 && float(iy) == py) --iy;
    ix = std::clamp(ix, 0, m.width - 1);
    iy = std::clamp(iy, 0, m.height - 1);
    tmax_x = exit_x(ix);
    tmax_y = exit_y(iy);
  };
  locate(t);

  // Only a start strictly inside a cell (not on its boundary) may skip an opaque start cell.
  bool skip = false;
  if (skip_start && t == ta) {
    const float px = ox + dx * t, py = oy + dy * t;
    skip = px != std::floor(px) && py != std::floor(py);
  }
  const bool blocks = !m.block_empty.empty();
  // The first cell of block b (of a row or column of n cells) that a ray moving by `step`
  // meets; its last is the first of the opposite direction.
  auto first_cell = [](int b, int step, int n) {
    return step > 0 ? b << kBlockShift : std::min(((b + 1) << kBlockShift) - 1, n - 1);
  };
  // The block level: the parameter at which the ray leaves block column bx / row by, the exit of
  // the block's last cell along the ray (the same formula, so the same bits).
  auto block_exit_x = [&](int bx) { return exit_x(first_cell(bx, -step_x, m.width)); };
  auto block_exit_y = [&](int by) { return exit_y(first_cell(by, -step_y, m.height)); };
  // Walks whole empty blocks from the empty block holding cell (ix, iy), one block per step.
  // Returns false when the ray leaves the grid or the interval on the way; otherwise t is where
  // it enters a block that holds something, and (ix, iy) is the cell the plain DDA would be in
  // there.
  auto walk_blocks = [&]() {
    int bx = ix >> kBlockShift, by = iy >> kBlockShift;
    float tbx = block_exit_x(bx), tby = block_exit_y(by);  // infinite along an axis not moved on
    bool moved_x, moved_y;
    do {
      t = std::min(tbx, tby);
      if (t >= tend) return false;
      moved_x = tbx <= tby, moved_y = tby <= tbx;  // both: exactly through a block corner
      if (moved_x && ((bx += step_x) < 0 || bx >= m.blocks_x)) return false;
      if (moved_y && ((by += step_y) < 0 || by >= m.blocks_y)) return false;
      if (moved_x) tbx = block_exit_x(bx);
      if (moved_y) tby = block_exit_y(by);
    } while (m.block_empty[std::size_t(by) * m.blocks_x + bx]);
    // Along an axis the ray moved on, the first cell of the new block; along the other, the
    // cell whose entry lies at or before t and whose exit beyond it (floor may round to either
    // side of a boundary).
    auto descend = [&](bool moved, int b, int step, int n, float o, float d, auto exit) {
      if (moved) return first_cell(b, step, n);
      int i = std::clamp(int(std::floor(o + d * t)), 0, n - 1);
      if (d == 0) return i;
      while (exit(i) <= t && i + step >= 0 && i + step < n) i += step;
      while (exit(i - step) > t && i - step >= 0 && i - step < n) i -= step;
      return i;
    };
    ix = descend(moved_x, bx, step_x, m.width, ox, dx, exit_x);
    iy = descend(moved_y, by, step_y, m.height, oy, dy, exit_y);
    tmax_x = exit_x(ix);
    tmax_y = exit_y(iy);
    return true;
  };

  while (t < tend) {
    const std::size_t idx = std::size_t(iy) * m.width + ix;
    const float step = m.step[idx];
    const float t_exit = std::min(std::min(tmax_x, tmax_y), tend);
    if (step > 0) {
      if (!(skip && step == kOpaque) && !visit(idx, step, t, t_exit)) return;
    } else {
      // Empty cell. In an empty block, walk the block level unless the distance-field jump
      // (see Medium::step) is longer than kJumpOverBlocks; otherwise jump when the jump leaves
      // the cell.
      if (blocks && step > -kJumpOverBlocks &&
          m.block_empty[std::size_t(iy >> kBlockShift) * m.blocks_x + (ix >> kBlockShift)]) {
        if (!walk_blocks()) return;
        skip = false;
        continue;
      }
      if (t - step > t_exit) {
        t -= step;
        if (t >= tend) break;
        locate(t);
        skip = false;
        continue;
      }
    }
    skip = false;
    t = t_exit;
    if (t >= tend) break;
    if (tmax_x < tmax_y) {
      ix += step_x;
      if (ix < 0 || ix >= m.width) break;
      tmax_x = exit_x(ix);
    } else if (tmax_y < tmax_x) {
      iy += step_y;
      if (iy < 0 || iy >= m.height) break;
      tmax_y = exit_y(iy);
    } else {
      // Exactly through a corner (the 45-degree rays from cell centres of a 4-direction
      // cascade do this): the ray only touches the two cells beside the corner at a point, so
      // it passes between them into the diagonal cell. Stepping x first or y first instead
      // would make results depend on the ray's orientation.
      ix += step_x;
      iy += step_y;
      if (ix < 0 || ix >= m.width || iy < 0 || iy >= m.height) break;
      tmax_x = exit_x(ix);
      tmax_y = exit_y(iy);
    }
  }
}

// The interval o + t*d, t in [ta, tb], with d of unit length. Outside the grid nothing emits
// or absorbs. Transport in a cell of extinction sigma over a length s: radiance Le*(1-e^-sigma s),
// transmittance e^-sigma s; an opaque cell returns Le and transmittance 0 to a ray entering it.
// With skip_start, a ray that starts strictly inside an opaque cell leaves it without
// interacting (the fluence of a wall cell is the light arriving at it).
Interval trace_interval(const Medium& m, float ox, float oy, float dx, float dy, float ta, float tb,
                        bool skip_start = false);

// The segment from point a to point b.
Interval trace_segment(const Medium& m, float ax, float ay, float bx, float by,
                       bool skip_start = false);

}  // namespace penumbra::flatland
