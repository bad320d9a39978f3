// Tracing a ray interval through the cell grid, as flatland/trace.hpp walk_cells() and
// trace_interval() (the CPU reference): exact cell traversal with the analytic transport of each
// cell and the distance-field jumps of Medium::step. The includer declares step_[] (extinction,
// or minus the jump length) and emission[] (3 floats per cell). The CPU's 8x8 empty-block level
// is left out: it skips the same cells and lands on the same parameters.
// A ray interval: radiance in rgb, transmittance in a.

float inf_() {
  return uintBitsToFloat(0x7f800000u);
}

// Front-to-back merge (seed 001 eq. 11).
vec4 merge_intervals(vec4 near, vec4 far) {
  return vec4(near.rgb + near.a * far.rgb, near.a * far.a);
}

bool clip_slab(float o, float d, float hi, inout float ta, inout float tb) {
  if (d == 0.0) return o >= 0.0 && o <= hi;
  precise float t0 = (0.0 - o) / d, t1 = (hi - o) / d;
  ta = max(ta, min(t0, t1));
  tb = min(tb, max(t0, t1));
  return true;
}

// Cell exits come from the origin with one formula (never accumulated), as on the CPU, so a ray
// through a corner meets both boundaries at the same parameter.
float cell_exit(int c, float o, float d, float inv) {
  precise float t = (float(c + (d > 0.0 ? 1 : 0)) - o) * inv;
  return d != 0.0 ? t : inf_();
}

vec4 trace_interval(int W, int H, float ox, float oy, float dx, float dy, float ta, float tb,
                    bool skip_start) {
  vec4 acc = vec4(0.0, 0.0, 0.0, 1.0);
  {  // fast exit: starts in empty space and ends within the jump allowed there
    precise float px = ox + dx * ta, py = oy + dy * ta;
    if (px >= 0.0 && py >= 0.0 && px < float(W) && py < float(H)) {
      float s = step_[uint(py) * uint(W) + uint(px)];
      if (s < 0.0 && tb - ta <= -s) return acc;
    }
  }
  float t = ta, tend = tb;
  if (!clip_slab(ox, dx, float(W), t, tend) || !clip_slab(oy, dy, float(H), t, tend) ||
      !(t < tend))
    return acc;
  const int step_x = dx > 0.0 ? 1 : -1, step_y = dy > 0.0 ? 1 : -1;
  const float inv_x = dx != 0.0 ? 1.0 / dx : 0.0, inv_y = dy != 0.0 ? 1.0 / dy : 0.0;
  int ix, iy;
  float tmax_x, tmax_y;
#define PENUMBRA_LOCATE(tt)                           \
  {                                                   \
    precise float lx = ox + dx * (tt), ly = oy + dy * (tt); \
    ix = int(floor(lx));                              \
    iy = int(floor(ly));                              \
    if (dx < 0.0 && float(ix) == lx) --ix;            \
    if (dy < 0.0 && float(iy) == ly) --iy;            \
    ix = clamp(ix, 0, W - 1);                         \
    iy = clamp(iy, 0, H - 1);                         \
    tmax_x = cell_exit(ix, ox, dx, inv_x);            \
    tmax_y = cell_exit(iy, oy, dy, inv_y);            \
  }
  PENUMBRA_LOCATE(t)
  bool skip = false;
  if (skip_start && t == ta) {
    precise float px = ox + dx * t, py = oy + dy * t;
    skip = px != floor(px) && py != floor(py);
  }
  while (t < tend) {
    const uint idx = uint(iy) * uint(W) + uint(ix);
    const float s = step_[idx];
    const float t_exit = min(min(tmax_x, tmax_y), tend);
    if (s > 0.0) {
      const bool opaque = isinf(s);
      if (!(skip && opaque)) {
        const vec3 c = vec3(emission[3 * idx], emission[3 * idx + 1], emission[3 * idx + 2]);
        if (opaque) {
          acc.rgb += acc.a * c;
          acc.a = 0.0;
          return acc;
        }
        const float tr = exp(-s * (t_exit - t));
        acc.rgb += acc.a * (1.0 - tr) * c;
        acc.a *= tr;
      }
    } else if (t - s > t_exit) {  // a distance-field jump that leaves the cell
      t -= s;
      if (t >= tend) break;
      PENUMBRA_LOCATE(t)
      skip = false;
      continue;
    }
    skip = false;
    t = t_exit;
    if (t >= tend) break;
    if (tmax_x < tmax_y) {
      ix += step_x;
      if (ix < 0 || ix >= W) break;
      tmax_x = cell_exit(ix, ox, dx, inv_x);
    } else if (tmax_y < tmax_x) {
      iy += step_y;
      if (iy < 0 || iy >= H) break;
      tmax_y = cell_exit(iy, oy, dy, inv_y);
    } else {  // exactly through a corner: into the diagonal cell, as on the CPU
      ix += step_x;
      iy += step_y;
      if (ix < 0 || ix >= W || iy < 0 || iy >= H) break;
      tmax_x = cell_exit(ix, ox, dx, inv_x);
      tmax_y = cell_exit(iy, oy, dy, inv_y);
    }
  }
#undef PENUMBRA_LOCATE
  return acc;
}

// The segment from a to b.
vec4 trace_segment(int W, int H, vec2 a, vec2 b, bool skip_start) {
  precise vec2 v = b - a;
  precise float len = sqrt(v.x * v.x + v.y * v.y);
  if (len == 0.0) return vec4(0.0, 0.0, 0.0, 1.0);
  return trace_interval(W, H, a.x, a.y, v.x / len, v.y / len, 0.0, len, skip_start);
}

// The four probes of a grid (spacing s, n probes a side) around a position with bilinear
// weights, probe a at (x[a & 1], y[a >> 1]), clamped at the edge (rc.cpp bilinear()).
void footprint(int s, ivec2 n, vec2 p, out ivec2 fx, out ivec2 fy, out vec4 w) {
  precise float u = p.x / float(s) - 0.5, v = p.y / float(s) - 0.5;
  const float fu0 = floor(u), fv0 = floor(v);
  precise float fu = u - fu0, fv = v - fv0;
  fx = clamp(ivec2(int(fu0), int(fu0) + 1), 0, n.x - 1);
  fy = clamp(ivec2(int(fv0), int(fv0) + 1), 0, n.y - 1);
  w = vec4((1.0 - fu) * (1.0 - fv), fu * (1.0 - fv), (1.0 - fu) * fv, fu * fv);
}
