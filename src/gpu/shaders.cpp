// SPIR-V words written by glslc -mfmt=num (see CMakeLists.txt).
#include "gpu/shaders.hpp"

namespace penumbra::gpu::shaders {
namespace {

const std::uint32_t kMedium[] = {
#include "medium.comp.inc"
};
const std::uint32_t kJfaSeed[] = {
#include "jfa_seed.comp.inc"
};
const std::uint32_t kJfaPass[] = {
#include "jfa_pass.comp.inc"
};
const std::uint32_t kJfaDistance[] = {
#include "jfa_distance.comp.inc"
};
const std::uint32_t kCrossBlur[] = {
#include "cross_blur.comp.inc"
};

}  // namespace

std::span<const std::uint32_t> medium() {
  return kMedium;
}
std::span<const std::uint32_t> jfa_seed() {
  return kJfaSeed;
}
std::span<const std::uint32_t> jfa_pass() {
  return kJfaPass;
}
std::span<const std::uint32_t> jfa_distance() {
  return kJfaDistance;
}
std::span<const std::uint32_t> cross_blur() {
  return kCrossBlur;
}

}  // namespace penumbra::gpu::shaders
