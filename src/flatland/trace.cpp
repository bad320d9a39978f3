#include "flatland/trace.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace penumbra {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Clips [ta, tb] to the grid box [0, w] x [0, h]. Returns false when nothing is left.
bool clip_to_grid(float ox, float oy, float dx, float dy, float w, float h, float& ta, float& tb) {
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

}  // namespace

Interval trace_interval(const Medium& m, float ox, float oy, float dx, float dy, float ta, float tb,
                        bool skip_start) {
  Interval out = Interval::empty();
  // Fast exit: an interval that starts in an empty cell and ends within the jump allowed from
  // there meets nothing (most short intervals away from walls).
  {
    const float px = ox + dx * ta, py = oy + dy * ta;
    if (px >= 0.0f && py >= 0.0f && px < float(m.width) && py < float(m.height)) {
      const float step = m.step[std::size_t(py) * m.width + std::size_t(px)];
      if (step < 0.0f && tb - ta <= -step) return out;
    }
  }
  float t = ta, tend = tb;
  if (!clip_to_grid(ox, oy, dx, dy, float(m.width), float(m.height), t, tend)) return out;
  const int step_x = dx > 0 ? 1 : -1, step_y = dy > 0 ? 1 : -1;
  // Cell exits are always computed from the origin with the same formula (never accumulated),
  // so a ray that jumped meets every later cell boundary at exactly the same parameter.
  const float inv_x = dx != 0 ? 1.0f / dx : 0.0f, inv_y = dy != 0 ? 1.0f / dy : 0.0f;
  auto exit_x = [&](int cx) { return dx != 0 ? (float(cx + (dx > 0)) - ox) * inv_x : kInf; };
  auto exit_y = [&](int cy) { return dy != 0 ? (float(cy + (dy > 0)) - oy) * inv_y : kInf; };

  int ix = 0, iy = 0;
  float tmax_x = kInf, tmax_y = kInf;
  // Locates the cell the ray occupies just after parameter t, and its exit parameters.
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

  while (t < tend) {
    const std::size_t idx = std::size_t(iy) * m.width + ix;
    const float step = m.step[idx];
    const float t_exit = std::min(std::min(tmax_x, tmax_y), tend);
    if (step > 0) {
      const Cell& c = m.cells[idx];
      if (step == kOpaque) {
        if (!skip) {
          out.r += out.t * c.r;
          out.g += out.t * c.g;
          out.b += out.t * c.b;
          out.t = 0;
          return out;
        }
      } else {
        const float tr = std::exp(-step * (t_exit - t));
        const float a = out.t * (1.0f - tr);
        out.r += a * c.r;
        out.g += a * c.g;
        out.b += a * c.b;
        out.t *= tr;
      }
    } else if (step < 0) {
      t -= step;  // jump through empty space (see Medium::step)
      if (t >= tend) break;
      locate(t);
      skip = false;
      continue;
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
  return out;
}

Interval trace_segment(const Medium& m, float ax, float ay, float bx, float by, bool skip_start) {
  const float vx = bx - ax, vy = by - ay;
  const float len = std::sqrt(vx * vx + vy * vy);
  if (len == 0.0f) return Interval::empty();
  return trace_interval(m, ax, ay, vx / len, vy / len, 0.0f, len, skip_start);
}

}  // namespace penumbra
