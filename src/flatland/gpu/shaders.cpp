// SPIR-V words written by glslc -mfmt=num (see CMakeLists.txt).
#include "flatland/gpu/shaders.hpp"

namespace penumbra::flatland::gpu::shaders {
namespace {

const std::uint32_t k_medium[] = {
#include "medium.comp.inc"
};
const std::uint32_t k_jfa_seed[] = {
#include "jfa_seed.comp.inc"
};
const std::uint32_t k_jfa_pass[] = {
#include "jfa_pass.comp.inc"
};
const std::uint32_t k_jfa_distance[] = {
#include "jfa_distance.comp.inc"
};
const std::uint32_t k_jfa_jump[] = {
#include "jfa_jump.comp.inc"
};
const std::uint32_t k_cross_blur[] = {
#include "cross_blur.comp.inc"
};
const std::uint32_t k_hrc_world[] = {
#include "hrc_world.comp.inc"
};
const std::uint32_t k_hrc_view[] = {
#include "hrc_view.comp.inc"
};
const std::uint32_t k_hrc_fan_clear[] = {
#include "hrc_fan_clear.comp.inc"
};
const std::uint32_t k_rc_merge[] = {
#include "rc_merge.comp.inc"
};
const std::uint32_t k_rc_fluence[] = {
#include "rc_fluence.comp.inc"
};
const std::uint32_t k_bounce[] = {
#include "bounce.comp.inc"
};
const std::uint32_t k_hrc_trace[] = {
#include "hrc_trace.comp.inc"
};
const std::uint32_t k_hrc_trace_f16[] = {
#include "hrc_trace_f16.comp.inc"
};
const std::uint32_t k_hrc_merge_up[] = {
#include "hrc_merge_up.comp.inc"
};
const std::uint32_t k_hrc_merge_up_f16[] = {
#include "hrc_merge_up_f16.comp.inc"
};
const std::uint32_t k_hrc_merge_down[] = {
#include "hrc_merge_down.comp.inc"
};
const std::uint32_t k_hrc_merge_down_f16[] = {
#include "hrc_merge_down_f16.comp.inc"
};
const std::uint32_t k_hrc_fan[] = {
#include "hrc_fan.comp.inc"
};
const std::uint32_t k_hrc_fan_f16[] = {
#include "hrc_fan_f16.comp.inc"
};
const std::uint32_t k_hrc_gather[] = {
#include "hrc_gather.comp.inc"
};
const std::uint32_t k_hrc_gather_f16[] = {
#include "hrc_gather_f16.comp.inc"
};

}  // namespace

// One accessor per shader; HRC's T and R kernels choose their storage.
#define PENUMBRA_SHADER(name)             \
  std::span<const std::uint32_t> name() { \
    return k_##name;                      \
  }
#define PENUMBRA_SHADER_F16(name)                 \
  std::span<const std::uint32_t> name(bool f16) { \
    if (f16) return k_##name##_f16;               \
    return k_##name;                              \
  }
PENUMBRA_SHADER(medium)
PENUMBRA_SHADER(jfa_seed)
PENUMBRA_SHADER(jfa_pass)
PENUMBRA_SHADER(jfa_distance)
PENUMBRA_SHADER(jfa_jump)
PENUMBRA_SHADER(cross_blur)
PENUMBRA_SHADER(hrc_world)
PENUMBRA_SHADER(hrc_view)
PENUMBRA_SHADER(hrc_fan_clear)
PENUMBRA_SHADER(rc_merge)
PENUMBRA_SHADER(rc_fluence)
PENUMBRA_SHADER(bounce)
PENUMBRA_SHADER_F16(hrc_trace)
PENUMBRA_SHADER_F16(hrc_merge_up)
PENUMBRA_SHADER_F16(hrc_merge_down)
PENUMBRA_SHADER_F16(hrc_gather)
PENUMBRA_SHADER_F16(hrc_fan)
#undef PENUMBRA_SHADER
#undef PENUMBRA_SHADER_F16

}  // namespace penumbra::flatland::gpu::shaders
