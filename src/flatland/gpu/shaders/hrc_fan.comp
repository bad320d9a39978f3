#version 450
#extension GL_GOOGLE_include_directive : require
#include "storage.glsl"
// HrcOptions::wall_fan, quadrant d (hrc.cpp fan_light): the light at each cell of the fan's
// list (hrc::fan_cells, the CPU's), through 2 rays per cone of cascade n, each traced from the
// cell's centre (from where it leaves an open cell) to the first probe column of the cascade
// more than M / 2 cells ahead and merged with its cone of R_n there, between the two rows it
// lands between. One invocation per cell of the list; the other cells keep hrc_fan_clear's -1
// (the gather then reads their quadrant as usual).
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Step { float step_[]; };
layout(std430, binding = 1) readonly buffer Emission { float emission[]; };
layout(std430, binding = 2) readonly buffer Rn { stored_t rn[]; };
layout(std430, binding = 3) readonly buffer Angles { float angles[]; };
layout(std430, binding = 4) writeonly buffer Light { float light[]; };
layout(std430, binding = 5) readonly buffer Cells { uint fan[]; };
layout(push_constant) uniform Push {
  int W; int H; int d; int n; int P; int h; float er; float eg; float eb; uint count;
} p;

#include "trace.glsl"

vec2 world_point(float u, float v) {
  vec2 q;
  if (p.d == 0) q = vec2(u, v);
  else if (p.d == 1) q = vec2(float(p.W - 1) - v, u);
  else if (p.d == 2) q = vec2(float(p.W - 1) - u, float(p.H - 1) - v);
  else q = vec2(v, float(p.H - 1) - u);
  return q + 0.5;
}

void main() {
  // 1-D work folded into x and y (gpu::groups_1d), so no dimension passes the device limit.
  uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
  if (i >= p.count) return;
  uint cell = fan[i];
  int x = int(cell % uint(p.W)), y = int(cell / uint(p.W));
  uint c = cell * 3u;
  int u = p.d == 0 ? x : p.d == 1 ? y : p.d == 2 ? p.W - 1 - x : p.H - 1 - y;
  int v = p.d == 0 ? y : p.d == 1 ? p.W - 1 - x : p.d == 2 ? p.H - 1 - y : x;
  int M = 1 << p.n;
  int xq = (u + M / 2) / M + 1;
  float delta = float(xq * M - u);
  vec2 a0 = world_point(float(u), float(v));
  bool open = !isinf(step_[uint(y) * uint(p.W) + uint(x)]);
  vec3 env = vec3(p.er, p.eg, p.eb);
  precise vec3 sum = vec3(0.0);
  for (int a = 0; a < M; ++a) {
    float A = angles[uint(M - 1 + a)];
    uint col = (uint(a) * uint(p.P) + uint(xq)) * 3u * uint(p.h);
    for (int j = 0; j < 2; ++j) {
      precise float slope = (2.0 * float(a - (M >> 1)) + (2.0 * float(j) + 1.0) / 2.0) / float(M);
      precise float ve = float(v) + slope * delta;
      vec2 b = world_point(float(xq * M), ve), start = a0;
      if (open) {  // from where the ray leaves an open cell, as on the CPU
        precise vec2 dir = b - a0;
        precise float e = 0.5 / max(abs(dir.x), abs(dir.y));
        start = a0 + e * dir;
      }
      vec4 seg = trace_segment(p.W, p.H, start, b, true);
      int v0 = int(floor(ve));
      precise float f1 = ve - float(v0), f0 = 1.0 - f1;
      vec3 far[2];
      for (int i = 0; i < 2; ++i) {
        int row = v0 + i;
        if (xq >= p.P || row < 0 || row >= p.h)
          far[i] = env * A;
        else
          far[i] = vec3(float(rn[col + uint(row)]), float(rn[col + uint(p.h) + uint(row)]),
                        float(rn[col + 2u * uint(p.h) + uint(row)]));
      }
      precise vec3 cf = f0 * far[0] + (f1 > 0.0 ? f1 * far[1] : vec3(0.0));
      sum += 0.5 * (A * seg.rgb + seg.a * cf);
    }
  }
  light[c] = sum.r;
  light[c + 1u] = sum.g;
  light[c + 2u] = sum.b;
}
