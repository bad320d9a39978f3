#version 450
#extension GL_GOOGLE_include_directive : require
#include "storage.glsl"
// R_n from R_{n+1}, T_n and T_{n+1} (hrc.cpp merge_down, eqs. 14-17). Past the grid, and at the
// top level, a cone holds the environment over its angle.
layout(local_size_x = 64, local_size_y = 4) in;
layout(std430, binding = 0) readonly buffer Tn { stored_t tn[]; };
layout(std430, binding = 1) readonly buffer Tn1 { stored_t tn1[]; };
layout(std430, binding = 2) readonly buffer Rn1 { stored_t rn1[]; };
layout(std430, binding = 3) readonly buffer Angles { float angle[]; };  // level m at 2^m - 1
layout(std430, binding = 4) writeonly buffer Rn { stored_t rn[]; };
layout(push_constant) uniform Push {
  int h; int n; int P; int P1; int rows; int top; float er; float eg; float eb;
  float wd;  // HrcOptions::even_weight
} p;

vec4 get_t(int k, int x, int y) {  // T_n, always inside
  uint c = uint((k * p.P + x) * 4) * uint(p.h) + uint(y);
  return vec4(float(tn[c]), float(tn[c + uint(p.h)]), float(tn[c + 2u * uint(p.h)]), float(tn[c + 3u * uint(p.h)]));
}
vec4 get_t1(int k, int x, int y) {  // T_{n+1}, always inside
  uint c = uint((k * p.P1 + x) * 4) * uint(p.h) + uint(y);
  return vec4(float(tn1[c]), float(tn1[c + uint(p.h)]), float(tn1[c + 2u * uint(p.h)]), float(tn1[c + 3u * uint(p.h)]));
}
vec3 get_r(int j, int x, int y, float a) {  // R_{n+1}, or the environment over angle a
  if (p.top != 0 || x >= p.P1 || y < 0 || y >= p.h) return vec3(p.er * a, p.eg * a, p.eb * a);
  uint c = uint((j * p.P1 + x) * 3) * uint(p.h) + uint(y);
  return vec3(float(rn1[c]), float(rn1[c + uint(p.h)]), float(rn1[c + 2u * uint(p.h)]));
}

int vy(int n, int k) { return 2 * k - (1 << n); }

void main() {
  int y = int(gl_GlobalInvocationID.x), row = int(gl_GlobalInvocationID.y);
  if (y >= p.h || row >= p.rows) return;
  int a = row / p.P, x = row % p.P;
  int base = (1 << (p.n + 1)) - 1;
  float ap = angle[base + 2 * a + 1], am = angle[base + 2 * a];
  precise vec3 o;
  if (x % 2 == 1) {
    vec4 ep = get_t(a + 1, x, y), em = get_t(a, x, y);
    int xq = (x + 1) / 2;
    vec3 fp = get_r(2 * a + 1, xq, y + vy(p.n, a + 1), ap);
    vec3 fm = get_r(2 * a, xq, y + vy(p.n, a), am);
    o = ap * ep.rgb + ep.a * fp + am * em.rgb + em.a * fm;
  } else {
    int xp = x / 2, xq = xp + 1;
    vec4 ep = get_t1(2 * a + 2, xp, y), em = get_t1(2 * a, xp, y);
    vec3 f0p = get_r(2 * a + 1, xp, y, ap), f0m = get_r(2 * a, xp, y, am);
    vec3 f1p = get_r(2 * a + 1, xq, y + vy(p.n + 1, 2 * a + 2), ap);
    vec3 f1m = get_r(2 * a, xq, y + vy(p.n + 1, 2 * a), am);
    o = p.wd * (f0p + f0m) + (1.0 - p.wd) * (ap * ep.rgb + ep.a * f1p + am * em.rgb + em.a * f1m);
  }
  uint c = uint(row * 3) * uint(p.h) + uint(y);
  rn[c] = stored_t(o.r);
  rn[c + uint(p.h)] = stored_t(o.g);
  rn[c + 2u * uint(p.h)] = stored_t(o.b);
}
