// SPIR-V words written by glslc -mfmt=num (see CMakeLists.txt).
#include "gpu/shaders.hpp"

namespace penumbra::gpu::shaders {
namespace {

const std::uint32_t kMedium[] = {
#include "medium.comp.inc"
};

}  // namespace

std::span<const std::uint32_t> medium() {
  return kMedium;
}

}  // namespace penumbra::gpu::shaders
