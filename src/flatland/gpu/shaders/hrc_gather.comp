#version 450
#extension GL_GOOGLE_include_directive : require
#include "storage.glsl"
// A quadrant's fluence (hrc.cpp solve_with): R_0 at [u + 1, v], blurred over the cell's
// neighbours by eq. 21 when `blur` is set, after the near segment from the cell's edge, into the
// world's fluence through the rotation; the first quadrant writes, the others add, and the last
// adds the cell's own medium (own_transmittance).
layout(local_size_x = 64, local_size_y = 4) in;
layout(std430, binding = 0) readonly buffer R0 { stored_t r0[]; };
layout(std430, binding = 1) readonly buffer View { float view[]; };
layout(std430, binding = 2) buffer Fluence { float f[]; };
// hrc_fan's light at the fan's cells (-1 elsewhere), read when `fan` is set.
layout(std430, binding = 3) readonly buffer Fan { float fan_light[]; };
layout(push_constant) uniform Push {
  int w; int h; int hp; int pad; uint view_cells; int base; int su; int sv; int first; int near;
  float er; float eg; float eb; int blur; int last; float step; int fan;
} p;

const float quarter = 1.57079633;

uint at(int u, int v) { return uint(u * p.hp + p.pad + v); }

vec3 r0_of(int u, int v) {
  if (u + 1 >= p.w) return vec3(p.er, p.eg, p.eb) * quarter;
  uint c = uint((u + 1) * 3) * uint(p.h) + uint(v);
  return vec3(float(r0[c]), float(r0[c + uint(p.h)]), float(r0[c + 2u * uint(p.h)]));
}

float tau(uint i) { return view[3u * p.view_cells + i]; }

// hrc.hpp own_transmittance: 4-point Gauss-Legendre over a quadrant.
float own_transmittance(float t) {
  if (t == 1.0) return 1.0;
  const float sec[4] = float[4](1.001488695, 1.034556040, 1.156447476, 1.343009689);
  const float weight[4] = float[4](0.17392742255, 0.32607257745, 0.32607257745, 0.17392742255);
  float l = log(t);
  precise float m = 0.0;
  for (int i = 0; i < 4; ++i) m += weight[i] * exp(l * sec[i]);
  return m;
}

void main() {
  int v = int(gl_GlobalInvocationID.x), u = int(gl_GlobalInvocationID.y);
  if (v >= p.h || u >= p.w) return;
  vec3 q = r0_of(u, v);
  uint own = at(u, v);
  float t_own = tau(own);
  if (p.blur != 0 && t_own != 0.0) {
    // hrc.cpp blur_column, in its order: left, right, up, down.
    precise vec3 sum = 4.0 * q;
    precise float weight = 4.0;
    precise float opacity = 1.0 - t_own * t_own;
    const ivec2 side[4] = ivec2[4](ivec2(-1, 0), ivec2(1, 0), ivec2(0, -1), ivec2(0, 1));
    for (int k = 0; k < 4; ++k) {
      int nu = u + side[k].x, nv = v + side[k].y;
      if (nu < 0 || nv < 0 || nu >= p.w || nv >= p.h) continue;
      float tn = tau(at(nu, nv));
      if (tn == 0.0) continue;
      precise float on = 1.0 - tn * tn;
      if (abs(on - opacity) > p.step) continue;
      sum += r0_of(nu, nv);
      weight += 1.0;
    }
    q = sum / weight;
  }
  if (p.near != 0) {
    uint next = own + uint(p.hp);
    float t_next = tau(next);
    precise float w_next = 1.0 - t_next;
    precise vec3 e = w_next * vec3(view[next], view[p.view_cells + next], view[2u * p.view_cells + next]);
    q = quarter * e + t_next * q;
  }
  uint i = uint(p.base + u * p.su + v * p.sv) * 3u;
  // A cell of the fan takes its light in place of its quadrant's read (hrc.cpp).
  if (p.fan != 0 && fan_light[i] >= 0.0)
    q = vec3(fan_light[i], fan_light[i + 1u], fan_light[i + 2u]);
  if (p.first != 0) {
    f[i] = q.r; f[i + 1u] = q.g; f[i + 2u] = q.b;
    return;
  }
  precise vec3 sum = vec3(f[i], f[i + 1u], f[i + 2u]) + q;
  if (p.last != 0 && p.near != 0) {
    // An opaque own cell is left as if empty: its fluence is the light arriving at it.
    float m = t_own == 0.0 ? 1.0 : own_transmittance(t_own);
    precise float e = 6.28318531 * (1.0 - m);
    sum = e * vec3(view[own], view[p.view_cells + own], view[2u * p.view_cells + own]) + m * sum;
  }
  f[i] = sum.r; f[i + 1u] = sum.g; f[i + 2u] = sum.b;
}
