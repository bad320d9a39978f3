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

const std::uint32_t k_hrc_world[] = {
#include "hrc_world.comp.inc"
};
const std::uint32_t k_hrc_view[] = {
#include "hrc_view.comp.inc"
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
const std::uint32_t k_hrc_gather[] = {
#include "hrc_gather.comp.inc"
};
const std::uint32_t k_hrc_gather_f16[] = {
#include "hrc_gather_f16.comp.inc"
};
const std::uint32_t k_jfa_jump[] = {
#include "jfa_jump.comp.inc"
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

std::span<const std::uint32_t> hrc_world() {
  return k_hrc_world;
}
std::span<const std::uint32_t> hrc_view() {
  return k_hrc_view;
}
std::span<const std::uint32_t> hrc_trace(bool f16) {
  if (f16) return k_hrc_trace_f16;
  return k_hrc_trace;
}
std::span<const std::uint32_t> hrc_merge_up(bool f16) {
  if (f16) return k_hrc_merge_up_f16;
  return k_hrc_merge_up;
}
std::span<const std::uint32_t> hrc_merge_down(bool f16) {
  if (f16) return k_hrc_merge_down_f16;
  return k_hrc_merge_down;
}
std::span<const std::uint32_t> hrc_gather(bool f16) {
  if (f16) return k_hrc_gather_f16;
  return k_hrc_gather;
}
std::span<const std::uint32_t> jfa_jump() {
  return k_jfa_jump;
}
std::span<const std::uint32_t> rc_merge() {
  return k_rc_merge;
}
std::span<const std::uint32_t> rc_fluence() {
  return k_rc_fluence;
}
std::span<const std::uint32_t> bounce() {
  return k_bounce;
}
}  // namespace penumbra::gpu::shaders
