#version 450
// HrcOptions::wall_fan and near_fan (hrc.cpp fan_cells): 1 at the cells the fan gathers, 0
// elsewhere. Lit wall cells: opaque, with a cell that is not opaque among their 8 neighbours.
// With near > 0, also the cells that are not opaque within `near` cells along x and y of a
// light's rim: a cell of the scene's own emission (`lights`) with a cell that emits nothing
// among its 8 neighbours. Two passes, once per solve: `pass` 0 writes each cell's rim flag
// (into the fan's light buffer, free until the first quadrant's fan), pass 1 reads the flags
// around each cell (one read per cell of the window, not nine).
layout(local_size_x = 64, local_size_y = 4) in;
layout(std430, binding = 0) readonly buffer Step { float step_[]; };
layout(std430, binding = 1) readonly buffer Lights { float lights[]; };
layout(std430, binding = 2) buffer Rims { uint rims[]; };
layout(std430, binding = 3) writeonly buffer Cells { uint fan[]; };
layout(push_constant) uniform Push {
  int W; int H; int near; int pass;
} p;

uint at(int x, int y) { return uint(y) * uint(p.W) + uint(x); }
bool opaque(int x, int y) { return isinf(step_[at(x, y)]); }
bool emits(int x, int y) {
  uint i = at(x, y) * 3u;
  return lights[i] + lights[i + 1u] + lights[i + 2u] > 0.0;
}

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= p.W || y >= p.H) return;
  if (p.pass == 0) {
    bool rim = false;
    if (p.near > 0 && emits(x, y))
      for (int b = max(y - 1, 0); b <= min(y + 1, p.H - 1); ++b)
        for (int a = max(x - 1, 0); a <= min(x + 1, p.W - 1); ++a)
          if (!emits(a, b)) rim = true;
    rims[at(x, y)] = rim ? 1u : 0u;
    return;
  }
  bool in_fan = false;
  if (opaque(x, y)) {
    for (int b = max(y - 1, 0); b <= min(y + 1, p.H - 1); ++b)
      for (int a = max(x - 1, 0); a <= min(x + 1, p.W - 1); ++a)
        if (!opaque(a, b)) in_fan = true;
  } else if (p.near > 0) {
    for (int b = max(y - p.near, 0); b <= min(y + p.near, p.H - 1) && !in_fan; ++b)
      for (int a = max(x - p.near, 0); a <= min(x + p.near, p.W - 1) && !in_fan; ++a)
        in_fan = rims[at(a, b)] != 0u;
  }
  fan[at(x, y)] = in_fan ? 1u : 0u;
}
