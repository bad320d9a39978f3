#version 450
#extension GL_GOOGLE_include_directive : require
// Flatland RC, the fluence at every cell centre from merged cascade 0, as flatland/rc/rc.cpp
// fluence(): F = sum over the Q0 cones of 2pi/Q0 * radiance, bilinear over the probes the cell
// can see (weights times visibility), plain bilinear for a cell that sees none.
layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 0) readonly buffer Step { float step_[]; };
layout(std430, binding = 1) readonly buffer Emission { float emission[]; };
layout(std430, binding = 2) readonly buffer Cascade0 { vec4 r0[]; };
layout(std430, binding = 3) buffer Fluence { float f[]; };
// A cascade 0 larger than one binding is summed a slab of directions at a time: Cascade0 bound
// from direction k0 (its element base); the first slab writes, the others add. The first of
// several slabs keeps each cell's weights and normalisation for the others, so the visibility
// rays are traced once.
layout(std430, binding = 4) buffer Weights { vec4 weights[]; };
layout(std430, binding = 5) buffer Norms { float norms[]; };
layout(push_constant) uniform Push {
  int w, h;
  int spacing, nx, ny, directions;
  float cone;
  int k0, first;
  uint base;
  int keep;  // more slabs follow: the first keeps its weights
} p;

#include "trace.glsl"

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= p.w || y >= p.h) return;
  const vec2 c = vec2(float(x) + 0.5, float(y) + 0.5);
  ivec2 fx, fy;
  vec4 fw;
  footprint(p.spacing, ivec2(p.nx, p.ny), c, fx, fy, fw);
  const uint cell = uint(y) * uint(p.w) + uint(x);
  vec4 wt;
  float norm;
  if (p.first != 0) {
    vec4 w = fw;
    float total = 0.0;
    for (int a = 0; a < 4; ++a) {
      if (w[a] == 0.0) continue;
      const vec2 q = vec2((float(fx[a & 1]) + 0.5) * float(p.spacing),
                          (float(fy[a >> 1]) + 0.5) * float(p.spacing));
      w[a] *= trace_segment(p.w, p.h, c, q, true).a;
      total += w[a];
    }
    const bool sees = total > 1e-6;
    wt = sees ? w : fw;
    norm = sees ? 1.0 / total : 1.0;
    if (p.keep != 0) {
      weights[cell] = wt;
      norms[cell] = norm;
    }
  } else {
    wt = weights[cell];
    norm = norms[cell];
  }
  vec3 sum = vec3(0.0);
  for (int k = 0; k < p.directions; ++k)  // the slab's directions
    for (int a = 0; a < 4; ++a) {
      if (wt[a] == 0.0) continue;
      sum += wt[a] *
             r0[p.base + (uint(k) * uint(p.ny) + uint(fy[a >> 1])) * uint(p.nx) + uint(fx[a & 1])]
                 .rgb;
    }
  const uint o = 3u * cell;
  const vec3 v = sum * norm * p.cone;
  if (p.first != 0) {
    f[o] = v.r;
    f[o + 1] = v.g;
    f[o + 2] = v.b;
  } else {
    f[o] += v.r;
    f[o + 1] += v.g;
    f[o + 2] += v.b;
  }
}
