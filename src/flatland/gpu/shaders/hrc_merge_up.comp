#version 450
#extension GL_GOOGLE_include_directive : require
#include "storage.glsl"
// T_{n+1} from T_n (hrc.cpp merge_up, eqs. 18-20). Reads past the grid are empty intervals.
layout(local_size_x = 64, local_size_y = 4) in;
layout(std430, binding = 0) readonly buffer Tn { stored_t tn[]; };
layout(std430, binding = 1) writeonly buffer Tn1 { stored_t tn1[]; };
layout(push_constant) uniform Push { int h; int n; int P; int P1; int rows; } p;

vec4 get_t(int k, int x, int y) {
  if (x >= p.P || y < 0 || y >= p.h) return vec4(0.0, 0.0, 0.0, 1.0);
  uint c = uint((k * p.P + x) * 4) * uint(p.h) + uint(y);
  return vec4(float(tn[c]), float(tn[c + uint(p.h)]), float(tn[c + 2u * uint(p.h)]), float(tn[c + 3u * uint(p.h)]));
}

vec4 merge(vec4 near, vec4 far) {
  precise vec4 m = vec4(near.rgb + near.a * far.rgb, near.a * far.a);
  return m;
}

int vy(int n, int k) { return 2 * k - (1 << n); }

void main() {
  int y = int(gl_GlobalInvocationID.x), row = int(gl_GlobalInvocationID.y);
  if (y >= p.h || row >= p.rows) return;
  int k2 = row / p.P1, x = row % p.P1, k = k2 / 2;
  precise vec4 o;
  if (k2 % 2 == 0) {
    o = merge(get_t(k, 2 * x, y), get_t(k, 2 * x + 1, y + vy(p.n, k)));
  } else {
    vec4 a = merge(get_t(k + 1, 2 * x, y), get_t(k, 2 * x + 1, y + vy(p.n, k + 1)));
    vec4 b = merge(get_t(k, 2 * x, y), get_t(k + 1, 2 * x + 1, y + vy(p.n, k)));
    o = 0.5 * (a + b);
  }
  uint c = uint(row * 4) * uint(p.h) + uint(y);
  tn1[c] = stored_t(o.r);
  tn1[c + uint(p.h)] = stored_t(o.g);
  tn1[c + 2u * uint(p.h)] = stored_t(o.b);
  tn1[c + 3u * uint(p.h)] = stored_t(o.a);
}
