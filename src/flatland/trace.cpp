#include "flatland/trace.hpp"

namespace penumbra::flatland {
Interval trace_interval(const Medium& m, float ox, float oy, float dx, float dy, float ta, float tb,
                        bool skip_start) {
  Interval out = Interval::empty();
  walk_cells(m, ox, oy, dx, dy, ta, tb, skip_start,
             [&](std::size_t idx, float step, float t0, float t1) {
               const Cell& c = m.cells[idx];
               if (step == kOpaque) {
                 out.r += out.t * c.r;
                 out.g += out.t * c.g;
                 out.b += out.t * c.b;
                 out.t = 0;
                 return false;
               }
               const float tr = std::exp(-step * (t1 - t0));
               const float a = out.t * (1.0f - tr);
               out.r += a * c.r;
               out.g += a * c.g;
               out.b += a * c.b;
               out.t *= tr;
               return true;
             });
  return out;
}

Interval trace_segment(const Medium& m, float ax, float ay, float bx, float by, bool skip_start) {
  const float vx = bx - ax, vy = by - ay;
  const float len = std::sqrt(vx * vx + vy * vy);
  if (len == 0.0f) return Interval::empty();
  return trace_interval(m, ax, ay, vx / len, vy / len, 0.0f, len, skip_start);
}

}  // namespace penumbra::flatland
