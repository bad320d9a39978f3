#version 450
// HrcOptions::wall_fan: -1 in the fan's light at every cell, once per solve, before hrc_fan
// writes the light of the cells it gathers (hrc::fan_cells, chosen on the CPU); the gather reads
// a cell's quadrant as usual where it finds -1.
layout(local_size_x = 256) in;
layout(std430, binding = 0) writeonly buffer Light { float light[]; };
layout(push_constant) uniform Push { uint values; } p;

void main() {
  // 1-D work folded into x and y (gpu::groups_1d), so no dimension passes the device limit.
  uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
  if (i < p.values) light[i] = -1.0;
}
