#version 450
#extension GL_GOOGLE_include_directive : require
// The final gather and shading of each pixel that sees a surface, as ssrc.cpp's Gather and
// render(): direct + albedo * the mean over the cascade-0 probes of its corners (--gather
// probe: their means; pixel: each probe's store weighted for the pixel's own normal). A pixel
// on the sky is left 0 (the host shades it). A store larger than one binding is read a slab of
// pixels at a time, bound from float `store_origin`.
layout(local_size_x = 64) in;

#include "ssrc.glsl"

layout(std430, binding = 0) readonly buffer Params { Global g; CascadeParams c[]; };
layout(std430, binding = 1) readonly buffer Dirs { vec2 dirs[]; };
layout(std430, binding = 2) readonly buffer Corners { uvec4 corners[]; };  // indices, weight bits
layout(std430, binding = 3) readonly buffer Count { float hits[]; };  // level 0: 1 on a hit
layout(std430, binding = 4) readonly buffer Light { float light[]; };  // direct rgb, albedo rgb
layout(std430, binding = 5) readonly buffer View { float view[]; };  // pixel: view, normal
layout(std430, binding = 6) readonly buffer Store { float store[]; };
layout(std430, binding = 7) readonly buffer Means { vec4 means[]; };  // probe: (rgb, has)
layout(std430, binding = 8) writeonly buffer Image { float image[]; };
layout(push_constant) uniform Push {
  uint first, count;  // the pixels of this dispatch
  uint store_origin;
  int per_pixel;  // --gather pixel
} p;

#include "ssrc_weights.glsl"

void main() {
  const uint gid = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
  if (gid >= p.count) return;
  const uint k = p.first + gid;
  if (!(hits[k] > 0.0)) {
    image[3u * k] = 0.0;
    image[3u * k + 1u] = 0.0;
    image[3u * k + 2u] = 0.0;
    return;
  }
  const vec3 direct = vec3(light[6u * k], light[6u * k + 1u], light[6u * k + 2u]);
  const vec3 albedo = vec3(light[6u * k + 3u], light[6u * k + 4u], light[6u * k + 5u]);
  const uvec4 ci = corners[2u * k];
  const vec4 cw = uintBitsToFloat(corners[2u * k + 1u]);
  precise vec3 sum = vec3(0.0);
  precise float used = 0.0;
  if (p.per_pixel == 0) {
    for (int j = 0; j < 4; ++j) {
      const vec4 m = means[ci[j]];
      if (!(cw[j] > 0.0) || m.w == 0.0) continue;
      sum = sum + m.rgb * cw[j];
      used = used + cw[j];
    }
  } else {
    const vec3 v = vec3(view[6u * k], view[6u * k + 1u], view[6u * k + 2u]);
    const vec3 n = vec3(view[6u * k + 3u], view[6u * k + 4u], view[6u * k + 5u]);
    const float nv = dot3(n, v);
    // Each corner's weighted sum in the CPU's order (directions, then bins), the total beside.
    precise float total = 0.0;
    precise vec3 e[4] = vec3[4](vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    const uint values = uint(g.q0 * g.bins) * 3u;
    float w[8];
    for (int d = 0; d < g.q0; ++d) {
      direction_weights(d, v, n, nv, w);
      for (int b = 0; b < g.bins; ++b) {
        total = total + w[b];
        for (int j = 0; j < 4; ++j) {
          if (!(cw[j] > 0.0)) continue;
          const uint f = ci[j] * values + uint(d * g.bins + b) * 3u - p.store_origin;
          e[j] = e[j] + vec3(store[f], store[f + 1u], store[f + 2u]) * w[b];
        }
      }
    }
    if (total > 0.0) {
      precise float inv = 1.0 / total;
      for (int j = 0; j < 4; ++j) {
        if (!(cw[j] > 0.0)) continue;
        sum = sum + e[j] * inv * cw[j];
        used = used + cw[j];
      }
    }
  }
  precise vec3 l = direct;
  if (used > 0.0) {
    precise vec3 mean = sum * (1.0 / used);
    l = direct + albedo * mean;
  }
  image[3u * k] = l.r;
  image[3u * k + 1u] = l.g;
  image[3u * k + 2u] = l.b;
}
