#version 450
// One level of the means' radiance from the level below, as ssrc.cpp's fill_radiance(): the
// count-weighted mean of the 2x2 texels under each texel (0 over misses only).
layout(local_size_x = 16, local_size_y = 16) in;

layout(std430, binding = 0) readonly buffer Count { float hits[]; };  // per texel
layout(std430, binding = 1) buffer Radiance { float radiance[]; };
layout(push_constant) uniform Push {
  int below_off, below_w, below_h;  // the level below: first texel and size
  int at_off, at_w, at_h;
} p;

void main() {
  const int x = int(gl_GlobalInvocationID.x), y = int(gl_GlobalInvocationID.y);
  if (x >= p.at_w || y >= p.at_h) return;
  precise vec3 sum = vec3(0.0);
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const int bx = 2 * x + dx, by = 2 * y + dy;
      if (bx >= p.below_w || by >= p.below_h) continue;
      const uint k = uint(p.below_off + by * p.below_w + bx);
      const vec3 r = vec3(radiance[3u * k], radiance[3u * k + 1u], radiance[3u * k + 2u]);
      sum = sum + r * hits[k];
    }
  const uint k = uint(p.at_off + y * p.at_w + x);
  const float n = hits[k];
  precise vec3 mean = vec3(0.0);
  if (n > 0.0) mean = sum * (1.0 / n);
  radiance[3u * k] = mean.r;
  radiance[3u * k + 1u] = mean.g;
  radiance[3u * k + 2u] = mean.b;
}
