#version 450
// The emission of the next bounce (flatland/render.cpp): the scene's own emission plus diffuse
// re-emission albedo * F / 2pi of the previous bounce's fluence.
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Emission { float le[]; };  // 3 per cell
layout(std430, binding = 1) readonly buffer Albedo { float albedo[]; };
layout(std430, binding = 2) readonly buffer Fluence { float f[]; };
layout(std430, binding = 3) writeonly buffer Out { float e[]; };
layout(push_constant) uniform Push { uint values; } p;  // 3 per cell

void main() {
  // 1-D work folded into x and y (gpu::groups_1d).
  uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
  if (i >= p.values) return;
  e[i] = le[i] + albedo[i] * f[i] * 0.15915494309189535;
}
