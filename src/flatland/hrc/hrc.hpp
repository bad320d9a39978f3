// Holographic radiance cascades on the CPU (seed 004, section 4).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "flatland/medium.hpp"
#include "penumbra/render.hpp"

namespace penumbra::hrc {

// Number of cascades N = ceil(log2(w)) for a view w cells long in the gathering direction.
int level_count(int w);

// Bytes HRC keeps alive: the acceleration structure T_0..T_N, two layers of R, the medium as
// planes (world layout and one rotated view) and the summed fluence, with the blur's copy (the
// largest of the two view orientations when the grid is not square).
std::uint64_t working_bytes(int width, int height, const HrcOptions& options);

// Bytes of the acceleration structure T_0..T_N and the two layers of R alone. For a 2^N x 2^N
// grid that is (N + 3 - 2^-N) 4^N (Vr + Vt) + 2 4^N Vr: the sum over n of 4^N (1 + 2^-n) for T
// (the seed prints + 2^-N, which the sum does not give).
std::uint64_t structure_bytes(int width, int height, Storage storage);

// The paper's count for a 2^N x 2^N grid (section 4.3.2) at the grid's larger side rounded up to
// a power of two: T = (N + 3 + 2^-N) 4^N (Vr + Vt) plus two layers of R, 2 4^N Vr.
std::uint64_t paper_bytes(int width, int height, const HrcOptions& options);

// Intervals traced through the cells (T_0..T_2 of the four quadrants); everything else is merged.
std::uint64_t traced_intervals(int width, int height);

// Largest emitted radiance half-precision storage holds without overflowing (the angular fluence
// of a quadrant is at most pi/2 times the brightest radiance).
inline constexpr float kHalfMaxRadiance = 65504.0f / 1.5707964f;

// Refuses a scene the storage cannot hold: in f16, emission above kHalfMaxRadiance (every stored
// value is at most the brightest radiance times pi/2, and a bounce re-emits no more than the
// light it received).
Status check_scene(const Scene& scene, const HrcOptions& options);

// The buffers of a solve, kept from one solve to the next of the same grid (bounces, the
// benchmarks, interactive use), so that the steady state allocates nothing. Buffers are not
// initialised when allocated: every kernel writes each element before it is read.
class Workspace {
 public:
  Workspace();
  ~Workspace();
  Workspace(Workspace&&) noexcept;
  Workspace& operator=(Workspace&&) noexcept;
  struct Impl;

 private:
  friend void solve(const Medium&, const Rgb&, const HrcOptions&, Workspace&, std::vector<float>&,
                    std::vector<StageTime>&);
  std::unique_ptr<Impl> impl_;
};

// Fluence at every cell centre into `fluence` (3 floats per cell, resized): the four quadrants
// on rotated views, summed, then the cross blur when enabled. Stage times are appended to
// `stages`.
void solve(const Medium& medium, const Rgb& environment, const HrcOptions& options,
           Workspace& workspace, std::vector<float>& fluence, std::vector<StageTime>& stages);

// Eq. 21, the final 1-cell cross blur of the fluence f (3 floats per cell) into out, given the
// transmittance over half a cell per cell (0: opaque). Neighbours whose opacity differs by more
// than kBlurOpacityStep are left out; opaque cells neither blur nor are blurred into others.
inline constexpr float kBlurOpacityStep = 0.5f;
void cross_blur(int W, int H, const float* tau_half, const float* f, float* out);

// What the GPU backend shares with this implementation, so both use the same numbers.
float cone_angle_of(int n, int a);      // eq. 13, cone a of cascade n
int view_pad();                         // empty cells around a rotated view
std::array<float, 3> traced_lengths();  // the transmittance planes' lengths (and their doubles)
struct TracedCell {
  int du, dv;
  int length;    // index into traced_lengths()
  bool squared;  // twice that length
};
std::vector<TracedCell> traced_cells(int n, int k);  // the cells ray k of T_n crosses, in order
struct ViewRotation {
  std::ptrdiff_t base, su, sv;  // view cell (u, v) is world cell base + u su + v sv
};
ViewRotation view_rotation(int d, int width, int height);  // quadrant d = +x, +y, -x, -y

}  // namespace penumbra::hrc
