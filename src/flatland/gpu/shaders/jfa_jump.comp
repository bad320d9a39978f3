#version 450
// Jump flooding, end for the tracers: the jump length of every empty cell written into the
// medium's step values, as flatland/medium.cpp build_distance_field().
layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 0) readonly buffer Seeds { int seed[]; };
layout(std430, binding = 1) buffer Step { float step_[]; };
layout(push_constant) uniform Push { int w; int h; } p;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= p.w || y >= p.h) return;
  const int i = y * p.w + x;
  if (step_[i] > 0.0) return;  // interacts
  const int s = seed[i];
  if (s < 0) {  // nothing interacts anywhere: a jump to beyond the grid
    step_[i] = -uintBitsToFloat(0x7f800000u);
    return;
  }
  precise float dx = float(s % p.w - x), dy = float(s / p.w - y);
  precise float d2 = dx * dx + dy * dy;
  // From anywhere in the cell a jump stays in empty cells for distance - sqrt(2); the extra half
  // cell absorbs JFA's rare inexact answers. Short jumps save less than cell stepping costs.
  precise float jump = sqrt(d2) - (1.4142136 + 0.5);
  step_[i] = jump > 2.0 ? -jump : 0.0;
}
