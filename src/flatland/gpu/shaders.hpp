// The compute shaders of src/gpu/shaders/, compiled to SPIR-V by glslc at build time and
// embedded in the library. HRC's T and R kernels come in two storage precisions (f16: T and R
// held as 16-bit floats).
#pragma once

#include <cstdint>
#include <span>

namespace penumbra::flatland::gpu::shaders {

std::span<const std::uint32_t> medium();        // medium.comp: extinction per cell
std::span<const std::uint32_t> jfa_seed();      // jump flooding: seeds
std::span<const std::uint32_t> jfa_pass();      // jump flooding: one pass of step k
std::span<const std::uint32_t> jfa_distance();  // jump flooding: distances
std::span<const std::uint32_t> cross_blur();    // HRC: eq. 21
std::span<const std::uint32_t> hrc_world();     // HRC: emission and transmittance planes
std::span<const std::uint32_t> hrc_view();      // HRC: a quadrant's rotated view
std::span<const std::uint32_t> hrc_trace(bool f16 = false);       // HRC: T_0..T_2
std::span<const std::uint32_t> hrc_merge_up(bool f16 = false);    // HRC: eqs. 18-20
std::span<const std::uint32_t> hrc_merge_down(bool f16 = false);  // HRC: eqs. 14-17
std::span<const std::uint32_t> hrc_gather(bool f16 = false);      // HRC: a quadrant's fluence
std::span<const std::uint32_t> hrc_fan(bool f16 = false);         // HRC: the fan's light
std::span<const std::uint32_t> hrc_fan_clear();                   // HRC: the fan's light cleared
std::span<const std::uint32_t> jfa_jump();    // jump flooding: jumps into the step values
std::span<const std::uint32_t> rc_merge();    // RC: one cascade, traced and merged
std::span<const std::uint32_t> rc_fluence();  // RC: fluence from cascade 0
std::span<const std::uint32_t> bounce();      // emission of the next bounce

}  // namespace penumbra::flatland::gpu::shaders
