#version 450
#extension GL_GOOGLE_include_directive : require
// --gather probe: each cascade-0 probe's cosine-weighted mean radiance about its own normal and
// view vector, as ssrc.cpp's Gather::prepare_probes() (has = 0: on the sky, or facing away).
layout(local_size_x = 64) in;

#include "ssrc.glsl"

layout(std430, binding = 0) readonly buffer Params { Global g; CascadeParams c[]; };
layout(std430, binding = 1) readonly buffer Dirs { vec2 dirs[]; };  // cascade 0's come first
layout(std430, binding = 2) readonly buffer Probes { vec4 probes[]; };
layout(std430, binding = 3) readonly buffer Store { float store[]; };
layout(std430, binding = 4) writeonly buffer Means { vec4 means[]; };  // (rgb, has)
layout(push_constant) uniform Push {
  uint first, count;  // the probes of this dispatch
  uint store_origin;  // where Store is bound from, in floats
} p;

#include "ssrc_weights.glsl"

void main() {
  const uint gid = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
  if (gid >= p.count) return;
  const uint q = p.first + gid;
  means[q] = vec4(0.0);
  const vec4 p0 = probes[2u * q], p1 = probes[2u * q + 1u];
  if (p0.w == 0.0) return;
  precise vec3 to_eye = g.eye.xyz - p0.xyz;
  const vec3 v = normalize3(to_eye), n = p1.xyz;
  const float nv = dot3(n, v);
  // The sum runs over directions and bins in the CPU's order, the total alongside.
  precise float total = 0.0;
  precise vec3 e = vec3(0.0);
  const uint base = q * uint(g.q0 * g.bins) * 3u - p.store_origin;
  float w[8];
  for (int d = 0; d < g.q0; ++d) {
    direction_weights(d, v, n, nv, w);
    for (int b = 0; b < g.bins; ++b) {
      total = total + w[b];
      const uint f = base + uint(d * g.bins + b) * 3u;
      e = e + vec3(store[f], store[f + 1u], store[f + 2u]) * w[b];
    }
  }
  if (!(total > 0.0)) return;
  precise vec3 mean = e * (1.0 / total);
  means[q] = vec4(mean, 1.0);
}
