#version 450
// HRC's final 1-cell cross blur (seed 004, eq. 21), as flatland/hrc/hrc.cpp cross_blur(): 4 at
// the centre and 1 at each side, leaving out opaque neighbours, neighbours beyond the grid and
// those whose opacity differs by more than 0.5; opaque cells are copied.
layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 0) readonly buffer Tau { float tau_half[]; };
layout(std430, binding = 1) readonly buffer Fluence { float f[]; };
layout(std430, binding = 2) writeonly buffer Out { float o[]; };
// tau_half starts at tau_offset (the HRC world's first transmittance plane, or a buffer of its own).
layout(push_constant) uniform Push { int w; int h; float step; uint tau_offset; } p;

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= p.w || y >= p.h) return;
  int i = y * p.w + x;
  vec3 c = vec3(f[3 * i], f[3 * i + 1], f[3 * i + 2]);
  float t = tau_half[p.tau_offset + uint(i)];
  if (t == 0.0) {
    o[3 * i] = c.r;
    o[3 * i + 1] = c.g;
    o[3 * i + 2] = c.b;
    return;
  }
  precise float opacity = 1.0 - t * t;
  precise vec3 sum = 4.0 * c;
  precise float weight = 4.0;
  // Left, right, up, down: the CPU's order, so the sums round alike.
  const ivec2 side[4] = ivec2[4](ivec2(-1, 0), ivec2(1, 0), ivec2(0, -1), ivec2(0, 1));
  for (int k = 0; k < 4; ++k) {
    int nx = x + side[k].x, ny = y + side[k].y;
    if (nx < 0 || ny < 0 || nx >= p.w || ny >= p.h) continue;
    int j = ny * p.w + nx;
    float tj = tau_half[p.tau_offset + uint(j)];
    if (tj == 0.0) continue;
    precise float oj = 1.0 - tj * tj;
    if (abs(oj - opacity) > p.step) continue;
    sum += vec3(f[3 * j], f[3 * j + 1], f[3 * j + 2]);
    weight += 1.0;
  }
  o[3 * i] = sum.r / weight;
  o[3 * i + 1] = sum.g / weight;
  o[3 * i + 2] = sum.b / weight;
}
