// The table of 2D methods (flatland/method.hpp): each method's option check, memory estimate and
// solve, and the plan every render derives once.
#include <cmath>
#include <limits>
#include <string>

#include "flatland/gpu/method.hpp"
#include "flatland/method.hpp"
#include "flatland/pt/pt.hpp"
#include "flatland/rc/rc.hpp"
#include "io/json_reader.hpp"

namespace penumbra::flatland {
namespace {

Status bad(const std::string& what) {
  return Error{what};
}

// ---- rc: radiance cascades (seed 001, seed 002) ----

Status rc_check(Plan& p) {
  const RcOptions& rc = p.options.rc;
  if (rc.probe_spacing < 1 || rc.probe_spacing > 64)
    return bad("`rc.probe_spacing`: expected 1..64 cells, found " +
               std::to_string(rc.probe_spacing));
  if (rc.directions < 1 || rc.directions > 64)
    return bad("`rc.directions`: expected 1..64, found " + std::to_string(rc.directions));
  if (rc.branching != 2 && rc.branching != 4)
    return bad("`rc.branching`: expected 2 or 4, found " + std::to_string(rc.branching));
  if (!(rc.interval > 0.0f) || !std::isfinite(rc.interval))
    return bad("`rc.interval` t0: expected a number > 0, found " + io::format_number(rc.interval));
  if (rc.cascades < 0 || rc.cascades > 16)
    return bad("`rc.cascades`: expected 0 (automatic) or 1..16, found " +
               std::to_string(rc.cascades));
  if (rc.extend) {
    if (rc.fix == MergeFix::bilinear)
      return bad(
          "`rc.extend`: interval extension builds each probe's own interval, which the bilinear "
          "fix does not use; choose `rc.fix` none or nearest");
    if (rc.preaverage) return bad("`rc.extend`: cannot be combined with `rc.preaverage`");
    if (!(rc.extend_length >= 1.0f) || !std::isfinite(rc.extend_length))
      return bad("`rc.extend_length`: expected a number >= 1, found " +
                 io::format_number(rc.extend_length));
  }
  // The derived count grows as t0 shrinks; spacing s0 * 2^n and Q0 * b^n must stay sane.
  const int count = rc.cascades > 0
                        ? rc.cascades
                        : rc::cascade_count(p.width, p.height, rc.interval, rc.branching);
  if (count > 16)
    return bad("`rc.interval` t0: " + io::format_number(rc.interval) + " needs " +
               std::to_string(count) +
               " cascades to reach the grid diagonal, more than 16; use a larger `rc.interval`");
  const std::int64_t top = rc::top_directions(rc.directions, rc.branching, count - 1);
  if (top > rc::kMaxDirections)
    return bad("`rc.cascades`: " + std::to_string(count) + " cascades give the top probes " +
               std::to_string(top) + " directions, more than " +
               std::to_string(rc::kMaxDirections) + "; use fewer `rc.cascades` or `rc.directions`");
  p.cascades = rc::plan_cascades(p.width, p.height, rc);
  for (const rc::Cascade& c : p.cascades)
    // Kernels index rows of (direction, probe row) with int.
    if (std::int64_t(c.directions) * c.probes_y > std::numeric_limits<int>::max())
      return bad("cascade " + std::to_string(c.n) + " is too large (" +
                 std::to_string(c.directions) + " directions x " + std::to_string(c.probes_y) +
                 " probe rows); use fewer `rc.directions` or a larger `rc.probe_spacing`");
  p.options.rc.cascades = int(p.cascades.size());
  return {};
}

std::uint64_t rc_bytes(const Plan& p) {
  return rc::cascade_bytes(p.cascades, p.options.rc) + p.cells() * 3 * sizeof(float);  // fluence
}

const char* rc_advice(const RenderOptions&) {
  return ", or use a larger `rc.probe_spacing`";
}

std::vector<float> rc_solve(CpuSolve& s, std::vector<StageTime>& stages) {
  return rc::solve(s.medium, s.scene.environment, s.plan.cascades, s.plan.options.rc, stages);
}

std::uint64_t rc_intervals(const Plan& p) {
  return rc::traced_intervals(p.cascades, p.options.rc);
}

// ---- hrc: holographic radiance cascades (seed 004) ----

Status hrc_check(Plan& p) {
  const int fan = p.options.hrc.wall_fan;
  if (fan < 0 || fan > kMaxWallFan)
    return bad("`hrc.wall_fan`: expected 0 (off) or 1.." + std::to_string(kMaxWallFan) +
               ", found " + std::to_string(fan));
  const int near = p.options.hrc.near_fan;
  if (near < 0 || near > kMaxNearFan)
    return bad("`hrc.near_fan`: expected 0 to " + std::to_string(kMaxNearFan) + " cells, found " +
               std::to_string(near));
  const float share = p.options.hrc.fan_share;
  if (!(share > 0.0f && share <= 1.0f))
    return bad("`hrc.fan_share`: expected a share of the cells in (0, 1], found " +
               io::format_number(share));
  const float w = p.options.hrc.even_weight;
  if (!(w >= 0.0f && w <= 1.0f))
    return bad("`hrc.even_weight`: expected a weight in [0, 1], found " + io::format_number(w));
  return {};
}

std::uint64_t hrc_bytes(const Plan& p) {
  return hrc::working_bytes(p.width, p.height, p.options.hrc);
}

const char* hrc_advice(const RenderOptions& o) {
  return o.hrc.storage == Storage::f32 ? ", or use `hrc.storage` f16" : "";
}

double hrc_largest_radiance(const RenderOptions& o) {
  return o.hrc.storage == Storage::f16 ? hrc::kHalfMaxRadiance : kLargestRadiance;
}

std::vector<float> hrc_solve(CpuSolve& s, std::vector<StageTime>& stages) {
  std::vector<float> f;
  // The near fan follows the rims of the scene's own lights, whatever a bounce adds.
  hrc::solve(s.medium, s.scene.environment, s.plan.options.hrc, s.hrc, f, stages,
             s.scene.emission.data());
  return f;
}

std::uint64_t hrc_intervals(const Plan& p) {
  return hrc::traced_intervals(p.width, p.height);
}

// ---- pt: the reference path tracer (seed 004 section 5) ----

Status pt_check(Plan& p) {
  const PtOptions& pt = p.options.pt;
  if (pt.spp < 0) return bad("`pt.spp`: expected >= 0, found " + std::to_string(pt.spp));
  if (!(pt.seconds >= 0) || !std::isfinite(pt.seconds))
    return bad("`pt.seconds`: expected a number of seconds >= 0, found " +
               io::format_number(pt.seconds));
  if (pt.spp == 0 && pt.seconds == 0)
    return bad("`pt.spp`: 0 (no limit) needs a time limit (`pt.seconds`)");
  return {};
}

std::uint64_t pt_bytes(const Plan& p) {
  return pt::working_bytes(p.width, p.height, p.options.pt);
}

const char* no_advice(const RenderOptions&) {
  return "";
}

std::vector<float> pt_solve(CpuSolve& s, std::vector<StageTime>&) {
  return pt::solve(s.medium, s.scene.albedo, s.scene.environment, s.plan.options, s.result);
}

// In the order of the Method enum.
const MethodEntry kMethods[] = {
    {Method::rc, "rc", "radiance cascades", "radiance cascades (seed 001, 002)", true, false,
     rc_check, rc_bytes, rc_advice, nullptr, rc_solve, rc_intervals, &gpu::kRcPasses},
    {Method::pt, "pt", "the path tracer",
     "the reference path tracer (converges to the exact fluence)", true, true, pt_check, pt_bytes,
     no_advice, nullptr, pt_solve, nullptr, nullptr},
    {Method::hrc, "hrc", "holographic radiance cascades",
     "holographic radiance cascades (seed 004)", false, false, hrc_check, hrc_bytes, hrc_advice,
     hrc_largest_radiance, hrc_solve, hrc_intervals, &gpu::kHrcPasses},
};

}  // namespace

std::span<const MethodEntry> method_table() {
  return kMethods;
}

std::vector<MethodInfo> methods() {
  std::vector<MethodInfo> list;
  for (const MethodEntry& m : kMethods)
    list.push_back({m.method, m.name, m.summary, m.gpu != nullptr, m.skips_empty_space});
  return list;
}

const MethodEntry& entry(Method m) {
  return kMethods[int(m)];
}

Expected<Plan> make_plan(int width, int height, const RenderOptions& o) {
  if (width < 1 || height < 1 || width > kMaxGridSide || height > kMaxGridSide)
    return Error{"grid: expected 1..16384 cells a side, found " + std::to_string(width) + "x" +
                 std::to_string(height)};
  if (o.bounces < 1 || o.bounces > 64)
    return Error{"`bounces`: expected 1..64, found " + std::to_string(o.bounces)};
  if (o.threads < 0) return Error{"`threads`: expected >= 0, found " + std::to_string(o.threads)};
  if (int(o.method) < 0 || std::size_t(o.method) >= std::size(kMethods))
    return Error{"`method`: unknown method " + std::to_string(int(o.method))};
  const MethodEntry& m = entry(o.method);
  if (o.device == Device::gpu) {
    if (!m.gpu)
      return Error{std::string("`device` gpu: ") + m.title + " runs on the CPU only (docs/GPU.md)"};
    if (Status s = gpu::supports(*m.gpu, o); !s) return s.error();
  }
  Plan plan;
  plan.width = width;
  plan.height = height;
  plan.options = o;
  if (m.check)
    if (Status s = m.check(plan); !s) return s.error();
  return plan;
}

std::uint64_t working_bytes(const Plan& p) {
  const RenderOptions& o = p.options;
  const std::uint64_t cells = p.cells();
  // On the GPU the host holds a copy of what the device's scene holds, and the fluence.
  if (o.device == Device::gpu) return cells * (7 + 3) * sizeof(float);
  const MethodEntry& m = entry(o.method);
  std::uint64_t bytes = cells * (sizeof(Cell) + sizeof(float));  // medium: emission and step
  if (m.skips_empty_space && o.distance_field) bytes += distance_field_bytes(p.width, p.height);
  if (m.skips_empty_space && o.blocks) bytes += blocks_bytes(p.width, p.height);
  bytes += m.working_bytes(p);
  if (!m.bounces_itself && o.bounces > 1)
    bytes += cells * 3 * sizeof(float);  // the previous bounce's fluence
  return bytes;
}

}  // namespace penumbra::flatland
