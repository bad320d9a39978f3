// The GPU ports of RC and HRC as method-table entries (flatland/gpu/method.hpp).
#include "flatland/gpu/method.hpp"

#include "flatland/gpu/distance.hpp"
#include "flatland/gpu/hrc.hpp"
#include "flatland/gpu/owners.hpp"
#include "flatland/gpu/rc.hpp"
#include "flatland/hrc/hrc.hpp"

namespace penumbra::flatland::gpu {
namespace {

// ---- rc ----

Status rc_unsupported(const RenderOptions& o) {
  if (o.rc.extend)
    return Error{"`device` gpu: interval extension runs on the CPU only; drop `rc.extend`"};
  return {};
}

std::uint64_t rc_bytes(const Plan& p) {
  std::uint64_t bytes = rc_device_bytes(p.width, p.height, p.cascades);
  if (p.options.distance_field) bytes += 2 * p.cells() * sizeof(std::int32_t);  // seeds
  return bytes;
}

void rc_bindings(const Plan& p, const DeviceInfo& info, std::vector<Binding>& out) {
  out.push_back({p.cells() * 4 * sizeof(float), "the fluence's visibility weights", ""});
  out.push_back({rc_smallest_binding(p.cascades, p.options.rc.branching) + info.offset_alignment,
                 "one direction of a cascade", ", a larger `rc.probe_spacing`"});
}

bool rc_jumps(const RenderOptions& o) {
  return o.distance_field;
}

void rc_owners(const RenderOptions& o, std::vector<Owner>& keep) {
  keep.push_back(kRc);
  if (o.distance_field) keep.push_back(kJumps);
}

Status rc_record(GpuSolve& s, Batch& batch, Buffer& emission) {
  return record_rc(s.cache, batch, s.plan.width, s.plan.height, s.step, emission, s.environment,
                   s.plan.cascades, s.plan.options.rc, s.fluence, s.binding_limit, s.alignment);
}

// ---- hrc ----

std::uint64_t hrc_bytes(const Plan& p) {
  return hrc_device_bytes(p.width, p.height, p.options.hrc);
}

void hrc_bindings(const Plan& p, const DeviceInfo&, std::vector<Binding>& out) {
  out.push_back(
      {hrc_largest_buffer(p.width, p.height, p.options.hrc.storage), "HRC's largest buffer", ""});
}

bool no_jumps(const RenderOptions&) {
  return false;
}

void hrc_owners(const RenderOptions& o, std::vector<Owner>& keep) {
  keep.push_back(kHrc);
  if (hrc::blurs_whole_fluence(o.hrc)) keep.push_back(kHrcBlur);
}

Status hrc_record(GpuSolve& s, Batch& batch, Buffer& emission) {
  const HrcOptions& o = s.plan.options.hrc;
  // The cells follow the scene's own lights and walls, the same for every bounce.
  if (s.hrc_fan.empty() && hrc::runs_fan(s.plan.width, s.plan.height, o))
    hrc::fan_cells(s.scene, o, s.hrc_fan);
  return record_hrc(s.cache, batch, s.plan.width, s.plan.height, s.step, emission, s.hrc_fan,
                    s.environment, o, s.fluence);
}

}  // namespace

const MethodPasses kRcPasses = {
    rc_unsupported, rc_bytes,  rc_bindings, ", a larger `rc.probe_spacing`",
    rc_jumps,       rc_owners, rc_record};
const MethodPasses kHrcPasses = {nullptr,  hrc_bytes,  hrc_bindings, "",
                                 no_jumps, hrc_owners, hrc_record};

}  // namespace penumbra::flatland::gpu
