#version 450
#extension GL_GOOGLE_include_directive : require
// Screen-space cascades, one cascade's (probe, direction) pairs: the march through the depth
// pyramid's level with an occlusion bitmask, then the sky where the ray left the screen or the
// upper cascade's merge, the extension over the probe's horizon and the bins, as ssrc.cpp's
// Cascade::probe(). A store larger than one binding is written a slab of pairs at a time: Out
// and Upper are bound from float `out_origin` and `up_origin` of their buffers.
layout(local_size_x = 64) in;

#include "ssrc.glsl"

layout(std430, binding = 0) readonly buffer Params { Global g; CascadeParams c[]; };
layout(std430, binding = 1) readonly buffer Dirs { vec2 dirs[]; };
layout(std430, binding = 2) readonly buffer Probes { vec4 probes[]; };    // (p, valid), (n, depth)
layout(std430, binding = 3) readonly buffer Corners { uvec4 corners[]; };  // indices, weight bits
// Per texel, ssrc.cpp's Texel: the plane's normal (3), its square, the plane's offset from the
// eye, the mean's depth, the depth range (lo > hi: only misses) and the solid's end.
layout(std430, binding = 4) readonly buffer Texels { float texels[]; };
layout(std430, binding = 5) readonly buffer Radiance { float radiance[]; };
layout(std430, binding = 6) readonly buffer Upper { float upper[]; };
layout(std430, binding = 7) writeonly buffer Out { float outs[]; };
layout(push_constant) uniform Push {
  int cascade;
  uint first, count;  // the pairs of this dispatch
  uint out_origin, up_origin;
  float on_plane2, tiny;  // ssrc.cpp's kOnPlane^2 and the parallel test's 1e-12
} p;

vec3 upper3(uint f) {
  f -= p.up_origin;
  return vec3(upper[f], upper[f + 1u], upper[f + 2u]);
}

vec3 sectors[32];

void main() {
  const uint gid = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
  if (gid >= p.count) return;
  const uint item = p.first + gid;
  const CascadeParams cp = c[p.cascade];
  const uint q = item / uint(cp.dirs);
  const int dir = int(item % uint(cp.dirs));
  const int n_sec = g.sectors, bins = g.bins, per_bin = g.per_bin;
  const uint out_at = item * uint(bins) * 3u - p.out_origin;
  const vec4 p0 = probes[2u * (uint(cp.probe_off) + q)];
  const vec4 p1 = probes[2u * (uint(cp.probe_off) + q) + 1u];
  if (p0.w == 0.0) {  // a probe on the sky: nothing
    for (int b = 0; b < 3 * bins; ++b) outs[out_at + uint(b)] = 0.0;
    return;
  }
  const vec3 P = p0.xyz, N = p1.xyz;
  const vec3 eye = g.eye.xyz, F = g.f.xyz, R = g.r.xyz, U = g.u.xyz;
  const float W = g.width, H = g.height, th = g.tan_half;
  const int px = int(q % uint(cp.nx)), py = int(q / uint(cp.nx));
  const int x = min(px * cp.spacing + cp.spacing / 2, g.image_w - 1);
  const int y = min(py * cp.spacing + cp.spacing / 2, g.image_h - 1);
  const float cx = float(x) + 0.5, cy = float(y) + 0.5;
  precise vec3 to_eye = eye - P;
  const vec3 v = normalize3(to_eye);

  const vec2 dd = dirs[uint(cp.dir_off + dir)];
  const float dx = dd.x, dy = dd.y;
  // Frame::ray_step and screen_direction.
  precise float sr = 2.0 * dx / W * th * W / H;
  precise float su = 2.0 * dy / H * th;
  precise vec3 rg = R * sr - U * su;
  precise vec3 sd = R * dx - U * dy;
  const vec3 T = slice_tangent(v, sd);
  const float horizon = slice_angle(-dot3(N, T), dot3(N, v));
  // Frame::ray(cx, cy).
  precise float sx = (2.0 * cx / W - 1.0) * th * W / H;
  precise float sy = (1.0 - 2.0 * cy / H) * th;
  precise vec3 g0 = F + R * sx + U * sy;

  for (int k = 0; k < n_sec; ++k) sectors[k] = vec3(0.0);
  uint occluded = 0u;
  bool left = false;
  const int level = cp.level;
  const float stretch = cp.stretch;
  for (int m = 0; m < cp.most; ++m) {
    const float r = cp.a + float(m + 1) * cp.step;
    precise float X = cx + r * dx;
    precise float Y = cy + r * dy;
    if (!(X >= 0.0 && Y >= 0.0 && X < W && Y < H)) {
      left = true;
      break;
    }
    const uint k = uint(cp.level_off) + uint(int(Y) >> level) * uint(cp.level_w) +
                   uint(int(X) >> level);
    const uint tk = 9u * k;
    const float lo = texels[tk + 6u], hi = texels[tk + 7u];
    if (!(lo <= hi)) continue;  // only misses: the sky occludes nothing
    const vec3 mn = vec3(texels[tk], texels[tk + 1u], texels[tk + 2u]);
    const float mn2 = texels[tk + 3u], plane = texels[tk + 4u], zc = texels[tk + 5u];
    const float grow = texels[tk + 8u];
    float t0 = 3.14159265358979, t1 = 0.0;
    for (int e = 0; e < 2; ++e) {
      precise float along = r + (e == 0 ? -0.5 : 0.5) * stretch;
      precise vec3 gg = g0 + rg * along;
      const float den = dot3(gg, mn);
      float z = zc;
      precise float den2 = den * den;
      precise float least = p.tiny * dot3(gg, gg) * mn2;
      if (den2 > least) z = plane / den;
      z = z < lo ? lo : (hi < z ? hi : z);  // std::clamp
      for (int s = 0; s < 2; ++s) {
        precise float depth = s == 0 ? z : z * grow;
        precise vec3 d = eye + gg * depth - P;
        float t = slice_angle(dot3(d, v), dot3(d, T));
        const float h = dot3(d, N);
        precise float h2 = h * h;
        precise float near_plane = p.on_plane2 * dot3(d, d);
        if (h <= 0.0 || h2 <= near_plane) t = t < horizon ? horizon : t;
        t0 = t < t0 ? t : t0;
        t1 = t1 < t ? t : t1;
      }
    }
    const uint bits = sector_bits(t0, t1, g.spr, n_sec);
    uint first = bits & ~occluded;
    if (first == 0u) continue;
    occluded |= bits;
    const vec3 light = vec3(radiance[3u * k], radiance[3u * k + 1u], radiance[3u * k + 2u]);
    for (; first != 0u; first &= first - 1u) {
      const int b = findLSB(first);
      precise vec3 sum = sectors[b] + light;
      sectors[b] = sum;
    }
  }
  if (cp.top != 0) left = true;

  const uvec4 ci = corners[2u * (uint(cp.corner_off) + q)];
  const vec4 cw = uintBitsToFloat(corners[2u * (uint(cp.corner_off) + q) + 1u]);
  const bool merges = cp.top == 0 && (cw.x > 0.0 || cw.y > 0.0 || cw.z > 0.0 || cw.w > 0.0);
  if (left || !merges) {
    // The open sectors see the sky (without the sun).
    for (int k = 0; k < n_sec; ++k) {
      if (((occluded >> uint(k)) & 1u) != 0u) continue;
      precise vec3 d = v * g.cos_sector[k] + T * g.sin_sector[k];
      vec3 sky = g.ground.rgb;
      if (!(d.y < 0.0)) {
        precise vec3 s = g.horizon.rgb + (g.zenith.rgb - g.horizon.rgb) * d.y;
        sky = s;
      }
      precise vec3 sum = sectors[k] + sky;
      sectors[k] = sum;
    }
  } else {
    // Per open sector, the mean of the two upper directions' bins, weighted by the corners.
    const uint open = ~occluded & (n_sec == 32 ? 0xffffffffu : ((1u << uint(n_sec)) - 1u));
    for (int j = 0; j < 4; ++j) {
      precise float w = 0.5 * cw[j];
      if (!(w > 0.0)) continue;
      const uint a = (ci[j] * uint(cp.up_dirs) + uint(2 * dir)) * uint(bins) * 3u;
      const uint b = a + uint(bins) * 3u;
      for (uint bits = open; bits != 0u; bits &= bits - 1u) {
        const int k = findLSB(bits);
        const uint at = uint(k / per_bin) * 3u;
        precise vec3 sum = sectors[k] + (upper3(a + at) + upper3(b + at)) * w;
        sectors[k] = sum;
      }
    }
  }
  // Below the probe's own surface: the last sector above it.
  const int above = above_of(horizon, g.spr, n_sec);
  if (above != 0)
    for (int k = above; k < n_sec; ++k) sectors[k] = sectors[above - 1];
  // Per bin: its sectors' mean over their solid angles.
  for (int b = 0; b < bins; ++b) {
    precise vec3 mean = vec3(0.0);
    for (int k = b * per_bin; k < (b + 1) * per_bin; ++k)
      mean = mean + sectors[k] * g.bin_weight[k];
    outs[out_at + uint(3 * b)] = mean.r;
    outs[out_at + uint(3 * b) + 1u] = mean.g;
    outs[out_at + uint(3 * b) + 2u] = mean.b;
  }
}
