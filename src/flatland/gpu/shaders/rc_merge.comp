#version 450
#extension GL_GOOGLE_include_directive : require
// Flatland RC, one cascade: every (direction, probe) of cascade n traced over its interval and
// merged with cascade n+1 (already merged with everything above) or, at the top, with the sky,
// as flatland/rc/rc.cpp merged_radiance() and merge_cascade(). Direction-first layout:
// entry (k * probes_y + j) * probes_x + i, one vec4 (radiance, transmittance) each.
layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Step { float step_[]; };
layout(std430, binding = 1) readonly buffer Emission { float emission[]; };
layout(std430, binding = 2) readonly buffer Dirs { vec2 dirs[]; };  // every cascade's, in turn
// Cascades larger than one binding are merged a slab of directions at a time: Out is bound from
// direction k0 (its element out_base), Upper from direction u_k0 (its element upper_base).
layout(std430, binding = 3) readonly buffer Upper { vec4 upper[]; };
layout(std430, binding = 4) writeonly buffer Out { vec4 out_[]; };
layout(push_constant) uniform Push {
  int w, h;
  int spacing, nx, ny, directions;  // cascade n
  float t_begin, t_end;
  uint dir_off;
  int u_spacing, u_nx, u_ny;  // cascade n+1
  float u_t_begin;
  uint u_dir_off;
  int branching, fix;  // fix: 0 none, 1 nearest, 2 bilinear (RcOptions::fix)
  int flags;           // 1: top cascade, 2: rays leave an opaque start cell, 4: pre-averaging
  float er, eg, eb;
  int k0, slab;         // the directions of this dispatch: k0 .. k0 + slab - 1
  int u_k0;             // the first direction of Upper's bound range
  uint out_base, upper_base;
} p;

vec4 upper_at(int kk, int qi, int qj) {
  return upper[p.upper_base + (uint(kk - p.u_k0) * uint(p.u_ny) + uint(qj)) * uint(p.u_nx) +
               uint(qi)];
}

#include "trace.glsl"

vec4 merged_radiance(int k, vec2 pos) {
  const bool skip = (p.flags & 2) != 0;
  const vec2 d = dirs[p.dir_off + uint(k)];
  if ((p.flags & 1) != 0)  // the environment lies beyond the last interval
    return merge_intervals(
        trace_interval(p.w, p.h, pos.x, pos.y, d.x, d.y, p.t_begin, p.t_end, skip),
        vec4(p.er, p.eg, p.eb, 0.0));
  const float inv_b = 1.0 / float(p.branching);
  const ivec2 un = ivec2(p.u_nx, p.u_ny);
  if (p.fix == 2) {
    // Bilinear fix: each child ray runs from this probe's interval start to the start of the
    // interval of each of the 4 upper probes.
    vec4 sum = vec4(0.0);
    ivec2 fx, fy;
    vec4 fw;
    footprint(p.u_spacing, un, pos, fx, fy, fw);
    for (int ci = 0; ci < p.branching; ++ci) {
      const int kk = p.branching * k + ci;
      const vec2 dd = dirs[p.u_dir_off + uint(kk)];
      for (int a = 0; a < 4; ++a) {
        if (fw[a] == 0.0) continue;
        const int qi = fx[a & 1], qj = fy[a >> 1];
        const vec2 q = vec2((float(qi) + 0.5) * float(p.u_spacing),
                            (float(qj) + 0.5) * float(p.u_spacing));
        const vec4 seg = trace_segment(p.w, p.h, pos + dd * p.t_begin, q + dd * p.u_t_begin, skip);
        const vec4 up = upper_at(kk, qi, qj);
        sum += merge_intervals(seg, up) * (fw[a] * inv_b);
      }
    }
    return sum;
  }
  vec4 far = vec4(0.0);
  if (p.fix == 0) {
    ivec2 fx, fy;
    vec4 fw;
    footprint(p.u_spacing, un, pos, fx, fy, fw);
    for (int ci = 0; ci < p.branching; ++ci)
      for (int a = 0; a < 4; ++a)
        far += upper_at(p.branching * k + ci, fx[a & 1], fy[a >> 1]) * (fw[a] * inv_b);
  } else {
    const int qi = clamp(int(floor(pos.x / float(p.u_spacing))), 0, p.u_nx - 1);
    const int qj = clamp(int(floor(pos.y / float(p.u_spacing))), 0, p.u_ny - 1);
    for (int ci = 0; ci < p.branching; ++ci)
      far += upper_at(p.branching * k + ci, qi, qj) * inv_b;
  }
  return merge_intervals(
      trace_interval(p.w, p.h, pos.x, pos.y, d.x, d.y, p.t_begin, p.t_end, skip), far);
}

void main() {
  // 1-D work folded into x and y (gpu::groups_1d).
  const uint e = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
  const uint per_direction = uint(p.nx) * uint(p.ny);
  if (e >= per_direction * uint(p.slab)) return;
  const int k = p.k0 + int(e / per_direction);
  const uint r = e % per_direction;
  const int i = int(r % uint(p.nx)), j = int(r / uint(p.nx));
  const vec2 pos = vec2((float(i) + 0.5) * float(p.spacing), (float(j) + 0.5) * float(p.spacing));
  if ((p.flags & 4) != 0) {
    // Pre-averaging (seed 000, section 5.1): the 2x2 sub-probes of the probe, averaged.
    const float hh = 0.25 * float(p.spacing);
    vec4 v = vec4(0.0);
    for (int a = 0; a < 4; ++a)
      v += merged_radiance(k, pos + vec2((a & 1) != 0 ? hh : -hh, (a & 2) != 0 ? hh : -hh)) * 0.25;
    out_[p.out_base + e] = v;
  } else {
    out_[p.out_base + e] = merged_radiance(k, pos);
  }
}
