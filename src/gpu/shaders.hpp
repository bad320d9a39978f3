// The compute shaders of src/gpu/shaders/, compiled to SPIR-V by glslc at build time and
// embedded in the library.
#pragma once

#include <cstdint>
#include <span>

namespace penumbra::gpu::shaders {

std::span<const std::uint32_t> medium();        // medium.comp: extinction per cell
std::span<const std::uint32_t> jfa_seed();      // jump flooding: seeds
std::span<const std::uint32_t> jfa_pass();      // jump flooding: one pass of step k
std::span<const std::uint32_t> jfa_distance();  // jump flooding: distances
std::span<const std::uint32_t> cross_blur();    // HRC: eq. 21

}  // namespace penumbra::gpu::shaders
