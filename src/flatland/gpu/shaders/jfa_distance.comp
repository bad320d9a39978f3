#version 450
// Jump flooding, end: the distance from each cell centre to its seed's, infinity for none.
layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 0) readonly buffer Seeds { int seed[]; };
layout(std430, binding = 1) writeonly buffer Distance { float distance[]; };
layout(push_constant) uniform Push { int w; int h; } p;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= p.w || y >= p.h) return;
  int s = seed[y * p.w + x];
  if (s < 0) {
    distance[y * p.w + x] = uintBitsToFloat(0x7f800000u);
    return;
  }
  precise float dx = float(s % p.w - x), dy = float(s / p.w - y);
  precise float d2 = dx * dx + dy * dy;
  distance[y * p.w + x] = sqrt(d2);
}
