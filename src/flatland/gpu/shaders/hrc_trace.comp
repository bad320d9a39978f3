#version 450
#extension GL_GOOGLE_include_directive : require
#include "storage.glsl"
// T_n for n <= 2 (hrc.cpp trace_level): ray k from probe (u = x 2^n, y) crosses a fixed pattern
// of cells; front to back, emission weighted by the transmittance so far.
layout(local_size_x = 64, local_size_y = 4) in;
layout(std430, binding = 0) readonly buffer View { float view[]; };
layout(std430, binding = 1) readonly buffer Pattern { ivec4 cells[]; };  // du, dv, length, squared
// (a corner: du, dv, -1 or -2, side)
layout(std430, binding = 2) readonly buffer Ranges { ivec2 ranges[]; };  // per k: first, count
layout(std430, binding = 3) writeonly buffer T { stored_t t[]; };
layout(push_constant) uniform Push { int h; int hp; int pad; int n; int P; int rows; uint view_cells; } p;

void main() {
  int y = int(gl_GlobalInvocationID.x), row = int(gl_GlobalInvocationID.y);
  if (y >= p.h || row >= p.rows) return;
  int k = row / p.P, u = (row % p.P) << p.n;
  precise float ar = 0.0, ag = 0.0, ab = 0.0, at = 1.0;
  ivec2 range = ranges[k];
  for (int s = range.x; s < range.x + range.y; ++s) {
    ivec4 c = cells[s];
    if (c.z < 0) {
      // hrc.cpp cross_corner: each opaque cell of the corner towards (du + 1, dv) and
      // (du, dv + c.w) stops half of the ray (c.z -1, Corners::half), or both together all of it
      // (c.z -2, Corners::walls).
      uint a = uint((u + c.x + 1) * p.hp + p.pad + c.y + y);
      uint b = uint((u + c.x) * p.hp + p.pad + c.y + c.w + y);
      float oa = view[3u * p.view_cells + a] == 0.0 ? 0.5 : 0.0;
      float ob = view[3u * p.view_cells + b] == 0.0 ? 0.5 : 0.0;
      if (c.z == -2) {  // Corners::walls: only two opaque cells stop it
        float both = oa * ob * 2.0;
        oa = both;
        ob = both;
      }
      precise float w = at;
      ar += w * (oa * view[a] + ob * view[b]);
      ag += w * (oa * view[p.view_cells + a] + ob * view[p.view_cells + b]);
      ab += w * (oa * view[2u * p.view_cells + a] + ob * view[2u * p.view_cells + b]);
      at = w * (1.0 - oa - ob);
      continue;
    }
    uint off = uint((u + c.x) * p.hp + p.pad + c.y + y);
    float tau = view[uint(3 + c.z) * p.view_cells + off];
    precise float tr = c.w != 0 ? tau * tau : tau;
    precise float wgt = at * (1.0 - tr);
    ar += wgt * view[off];
    ag += wgt * view[p.view_cells + off];
    ab += wgt * view[2u * p.view_cells + off];
    at *= tr;
  }
  uint o = uint(row * 4) * uint(p.h) + uint(y);
  t[o] = stored_t(ar);
  t[o + uint(p.h)] = stored_t(ag);
  t[o + 2u * uint(p.h)] = stored_t(ab);
  t[o + 3u * uint(p.h)] = stored_t(at);
}
