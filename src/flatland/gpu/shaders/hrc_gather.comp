#version 450
#extension GL_GOOGLE_include_directive : require
#include "storage.glsl"
// A quadrant's fluence (hrc.cpp solve_with): R_0 at [u + 1, v], after the near segment from the
// cell's centre, into the world's fluence through the rotation; the first quadrant writes, the
// others add.
layout(local_size_x = 64, local_size_y = 4) in;
layout(std430, binding = 0) readonly buffer R0 { stored_t r0[]; };
layout(std430, binding = 1) readonly buffer View { float view[]; };
layout(std430, binding = 2) buffer Fluence { float f[]; };
layout(push_constant) uniform Push {
  int w; int h; int hp; int pad; uint view_cells; int base; int su; int sv; int first; int near;
  float er; float eg; float eb;
} p;

void main() {
  int v = int(gl_GlobalInvocationID.x), u = int(gl_GlobalInvocationID.y);
  if (v >= p.h || u >= p.w) return;
  const float quarter = 1.57079633;
  vec3 q = vec3(p.er, p.eg, p.eb) * quarter;
  if (u + 1 < p.w) {
    uint c = uint((u + 1) * 3) * uint(p.h) + uint(v);
    q = vec3(float(r0[c]), float(r0[c + uint(p.h)]), float(r0[c + 2u * uint(p.h)]));
  }
  if (p.near != 0) {
    uint own = uint(u * p.hp + p.pad + v), next = own + uint(p.hp);
    float tau_own = view[3u * p.view_cells + own], t_next = view[3u * p.view_cells + next];
    float t_own = tau_own == 0.0 ? 1.0 : tau_own;
    precise float w_own = 1.0 - t_own, w_next = t_own * (1.0 - t_next);
    precise vec3 e = w_own * vec3(view[own], view[p.view_cells + own], view[2u * p.view_cells + own]) +
                     w_next * vec3(view[next], view[p.view_cells + next], view[2u * p.view_cells + next]);
    precise float t = t_own * t_next;
    q = quarter * e + t * q;
  }
  uint i = uint(p.base + u * p.su + v * p.sv) * 3u;
  if (p.first != 0) {
    f[i] = q.r; f[i + 1u] = q.g; f[i + 2u] = q.b;
  } else {
    f[i] += q.r; f[i + 1u] += q.g; f[i + 2u] += q.b;
  }
}
