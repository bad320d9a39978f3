#version 450
// Jump flooding, start: a cell that interacts (step > 0) is its own nearest seed; others have
// none (-1). flatland/medium.cpp jump_flood_distance() is the CPU reference.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Step { float step_[]; };
layout(std430, binding = 1) writeonly buffer Seeds { int seed[]; };
layout(push_constant) uniform Push { uint cells; } p;

void main() {
  // 1-D work folded into x and y (gpu::groups_1d), so no dimension passes the device limit.
  uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
  if (i >= p.cells) return;
  seed[i] = step_[i] > 0.0 ? int(i) : -1;
}
