#version 450
// The medium's extinction per cell: sigma = -ln(1 - opacity) per cell length, infinity for an
// opaque cell (flatland/medium.cpp extinction(), the CPU reference).
layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Opacity { float opacity[]; };
layout(std430, binding = 1) writeonly buffer Sigma { float sigma[]; };
layout(push_constant) uniform Push { uint cells; } p;

void main() {
  // 1-D work folded into x and y (gpu::groups_1d), so no dimension passes the device limit.
  uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
  if (i >= p.cells) return;
  float o = opacity[i];
  float s;
  if (o >= 1.0) {
    s = uintBitsToFloat(0x7f800000u);  // opaque
  } else if (o <= 0.0) {
    s = 0.0;
  } else if (o < 0.0625) {
    // log(1 - o) loses o's digits when o is small (GLSL has no log1p): the series, to o^6.
    s = o * (1.0 + o * (1.0 / 2.0 + o * (1.0 / 3.0 + o * (1.0 / 4.0 + o * (1.0 / 5.0 + o / 6.0)))));
  } else {
    s = -log(1.0 - o);
  }
  sigma[i] = s;
}
