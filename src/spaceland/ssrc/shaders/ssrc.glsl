// What the screen-space cascades' kernels share: the parameters (ssrc/gpu.cpp's Global and
// CascadeParams, the same layout), and the CPU's arithmetic (ssrc/ssrc.cpp) written out in the
// same order with `precise`, so that no multiply-add is fused where the CPU rounds twice: the
// GPU's bits then match the CPU's up to the last bit of a few library calls (sqrt, ceil).

struct Global {
  vec4 eye, f, r, u;              // the camera's frame (xyz)
  vec4 ground, horizon, zenith;   // the sky (rgb)
  float width, height, tan_half;  // the image and the field of view
  float spr;                      // sectors per radian
  int sectors, bins, per_bin, q0;
  int image_w, image_h, pad0, pad1;
  float cos_sector[32];
  float sin_sector[32];
  float bin_weight[32];  // each sector's share of its bin (its solid angle over the bin's)
  float cos_sum[36];  // 33 used
  float sin_sum[36];
};

struct CascadeParams {
  int level, level_w, level_off, most;  // the pyramid level read, its width, first texel; samples
  float a, step, stretch, pad;          // the interval's start, the sample step (pixels)
  int top, dirs, nx, spacing;           // the top cascade; directions; probe tiles
  int probe_off, corner_off, dir_off, up_dirs;  // into the probe, corner and direction tables
};

float dot3(vec3 a, vec3 b) {
  precise float d = a.x * b.x + a.y * b.y + a.z * b.z;
  return d;
}

vec3 normalize3(vec3 a) {
  precise float l = sqrt(dot3(a, a));
  return a / l;
}

// The unit vector in the slice of screen direction w about the view vector v.
vec3 slice_tangent(vec3 v, vec3 w) {
  precise vec3 d = w - v * dot3(v, w);
  return normalize3(d);
}

// ssrc.cpp slice_angle(): the angle from the view vector, a polynomial atan.
float slice_angle(float a, float b) {
  b = max(b, 0.0);
  const float ax = abs(a);
  const float lo = min(ax, b), hi = max(ax, b);
  if (!(hi > 0.0)) return 0.0;
  precise float q = lo / hi;
  precise float q2 = q * q;
  precise float t = ((-0.0464964749 * q2 + 0.15931422) * q2 - 0.327622764) * q2 * q + q;
  if (b > ax) t = 1.57079632679 - t;
  precise float r = a < 0.0 ? 3.14159265359 - t : t;
  return r;
}

// ssrc.cpp sector_bits(): the sectors whose centre angle [lo, hi] covers, as bits.
uint sector_bits(float lo, float hi, float spr, int n) {
  precise float a = lo * spr - 0.5;
  precise float b = hi * spr - 0.5;
  const int k1 = max(0, int(ceil(a)));
  const int k2 = min(n - 1, int(floor(b)));
  if (k1 > k2) return 0u;
  // 2 << 31 is 0 in 32 bits: minus one, every bit, as the CPU's 64-bit mask.
  const uint upto = (2u << uint(k2)) - 1u;
  const uint below = (1u << uint(k1)) - 1u;
  return upto & ~below;
}

// The first sector at or past the horizon's angle t (0..sectors): ssrc.cpp's `above`.
int above_of(float t, float spr, int sectors) {
  precise float a = t * spr - 0.5;
  return clamp(int(ceil(a)), 0, sectors);
}
