// Radiance intervals (seed 001, section 2.3): the radiance a ray segment picks up and its
// transmittance, and the one place where two adjacent intervals are merged.
#pragma once

namespace penumbra::flatland {

struct Interval {
  float r = 0, g = 0, b = 0;  // radiance L gathered along the segment, linear RGB
  float t = 1;                // transmittance T (beta in the paper) of the segment

  static constexpr Interval empty() { return {0, 0, 0, 1}; }
};

// Front-to-back merge (seed 001 eq. 11): L = L_near + T_near * L_far, T = T_near * T_far.
inline Interval merge_intervals(const Interval& near, const Interval& far) {
  return {near.r + near.t * far.r, near.g + near.t * far.g, near.b + near.t * far.b,
          near.t * far.t};
}

// Weighted accumulation, for interpolating intervals (merging is linear in the far interval).
inline void accumulate(Interval& sum, const Interval& x, float w) {
  sum.r += w * x.r;
  sum.g += w * x.g;
  sum.b += w * x.b;
  sum.t += w * x.t;
}

inline Interval zero_interval() {
  return {0, 0, 0, 0};
}

}  // namespace penumbra::flatland
