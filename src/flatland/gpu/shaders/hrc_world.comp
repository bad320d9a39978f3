#version 450
// HRC world planes (hrc.cpp build_world): emission r, g, b and the transmittance over the three
// traced lengths, per cell, row by row. Empty and opaque cells need no exp.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Emission { float emission[]; };  // 3 per cell
layout(std430, binding = 1) readonly buffer Step { float step_[]; };
layout(std430, binding = 2) writeonly buffer World { float world[]; };      // 6 planes
layout(push_constant) uniform Push { uint cells; float l0; float l1; float l2; } p;

void main() {
  // 1-D work folded into x and y (gpu::groups_1d), so no dimension passes the device limit.
  uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
  if (i >= p.cells) return;
  float sigma = step_[i] > 0.0 ? step_[i] : 0.0;
  bool opaque = isinf(sigma);
  world[i] = emission[3 * i];
  world[p.cells + i] = emission[3 * i + 1];
  world[2 * p.cells + i] = emission[3 * i + 2];
  float l[3] = float[3](p.l0, p.l1, p.l2);
  for (int k = 0; k < 3; ++k)
    world[(3 + k) * p.cells + i] = sigma == 0.0 ? 1.0 : opaque ? 0.0 : exp(-sigma * l[k]);
}
