#version 450
// One jump flooding pass of step k: each cell keeps the nearest seed among its own and those of
// the 8 cells k away. Ties go to the lower index, as on the CPU, so both give the same seeds.
layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 0) readonly buffer In { int seed_in[]; };
layout(std430, binding = 1) writeonly buffer Out { int seed_out[]; };
layout(push_constant) uniform Push { int w; int h; int k; } p;

// Squared distance in float, as the CPU computes it (no fused multiply-add).
precise float dist2(int x, int y, int s) {
  precise float dx = float(s % p.w - x), dy = float(s / p.w - y);
  precise float d = dx * dx + dy * dy;
  return d;
}

void main() {
  int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= p.w || y >= p.h) return;
  int best = seed_in[y * p.w + x];
  float best_d = best >= 0 ? dist2(x, y, best) : uintBitsToFloat(0x7f800000u);
  for (int oy = -p.k; oy <= p.k; oy += p.k) {
    int sy = y + oy;
    if (sy < 0 || sy >= p.h) continue;
    for (int ox = -p.k; ox <= p.k; ox += p.k) {
      int sx = x + ox;
      if (sx < 0 || sx >= p.w || (ox == 0 && oy == 0)) continue;
      int s = seed_in[sy * p.w + sx];
      if (s < 0) continue;
      float d = dist2(x, y, s);
      if (d < best_d || (d == best_d && s < best)) {
        best = s;
        best_d = d;
      }
    }
  }
  seed_out[y * p.w + x] = best;
}
