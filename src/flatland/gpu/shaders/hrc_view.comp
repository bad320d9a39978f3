#version 450
// One quadrant's rotated view of the world planes (hrc.cpp build_view): columns of hp = h + 2 pad
// cells, v fastest, with pad empty cells above and below and pad empty columns after.
layout(local_size_x = 64, local_size_y = 4) in;
layout(std430, binding = 0) readonly buffer World { float world[]; };
layout(std430, binding = 1) writeonly buffer View { float view[]; };
layout(push_constant) uniform Push {
  int w; int h; int hp; int pad; uint cells; uint view_cells; int base; int su; int sv;
} p;

void main() {
  int vv = int(gl_GlobalInvocationID.x), u = int(gl_GlobalInvocationID.y);
  int plane = int(gl_GlobalInvocationID.z);
  if (vv >= p.hp || u >= p.w + p.pad) return;
  int v = vv - p.pad;
  float value = plane < 3 ? 0.0 : 1.0;  // beyond the grid: nothing emits, nothing absorbs
  if (u < p.w && v >= 0 && v < p.h) value = world[uint(plane) * p.cells + uint(p.base + u * p.su + v * p.sv)];
  view[uint(plane) * p.view_cells + uint(u * p.hp + vv)] = value;
}
