// HRC passes on the GPU.
#include "flatland/gpu/hrc.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "flatland/gpu/owners.hpp"
#include "flatland/gpu/shaders.hpp"
#include "flatland/hrc/hrc.hpp"

namespace penumbra::flatland::gpu {

namespace {

// Eq. 21 as one timed pass: `tau` holds the transmittance over half a cell from element
// tau_offset on.
Status record_cross_blur(Cache& cache, Batch& batch, int W, int H, Buffer& tau,
                         std::uint32_t tau_offset, Buffer& in, Buffer& out) {
  struct {
    std::int32_t w, h;
    float step;
    std::uint32_t tau_offset;
  } push{W, H, hrc::kBlurOpacityStep, tau_offset};
  Expected<const Kernel*> k = cache.kernel("cross_blur", shaders::cross_blur(), 3, sizeof(push));
  if (!k) return k.error();
  batch.mark("cross blur");
  Buffer* b[] = {&tau, &in, &out};
  batch.dispatch(**k, b, &push, (std::uint32_t(W) + 15) / 16, (std::uint32_t(H) + 15) / 16);
  return {};
}

}  // namespace

Expected<std::vector<float>> cross_blur(const Context& c, int width, int height,
                                        const std::vector<float>& tau_half,
                                        const std::vector<float>& fluence) {
  const std::size_t n = std::size_t(width) * height;
  if (tau_half.size() != n || fluence.size() != 3 * n)
    return Error{"cross blur: inputs do not match the " + std::to_string(width) + "x" +
                 std::to_string(height) + " grid"};
  Cache cache(c);
  Expected<Buffer*> tau = cache.buffer(kScratch, "tau", n * sizeof(float), Memory::host);
  if (!tau) return tau.error();
  Expected<Buffer*> in = cache.buffer(kScratch, "in", 3 * n * sizeof(float), Memory::host);
  if (!in) return in.error();
  Expected<Buffer*> out = cache.buffer(kScratch, "out", 3 * n * sizeof(float), Memory::host);
  if (!out) return out.error();
  std::copy(tau_half.begin(), tau_half.end(), (*tau)->as<float>());
  std::copy(fluence.begin(), fluence.end(), (*in)->as<float>());
  Expected<Batch> batch = c.batch();
  if (!batch) return batch.error();
  if (Status st = record_cross_blur(cache, *batch, width, height, **tau, 0, **in, **out); !st)
    return st.error();
  if (Expected<std::vector<std::pair<std::string, double>>> r = batch->run(); !r) return r.error();
  const float* o = (*out)->as<float>();
  return std::vector<float>(o, o + 3 * n);
}

std::uint64_t hrc_device_bytes(int W, int H, const HrcOptions& o) {
  const hrc::Sizes sz = hrc::plan(W, H);
  const int levels = int(sz.t.size()) - 1;
  const std::uint64_t value = o.storage == Storage::f16 ? 2 : 4;  // a stored T or R value
  // The world planes, the gather's own fluence when the blur writes the result, the fan's light
  // (its cells' indices are in host memory).
  std::uint64_t bytes =
      std::uint64_t(W) * H *
      (6 + (hrc::blurs_whole_fluence(o) ? 3 : 0) + (hrc::runs_fan(W, H, o) ? 3 : 0)) *
      sizeof(float);
  bytes += 6 * std::uint64_t(sz.pad) * sizeof(float);  // view
  bytes += 2 * 3 * std::uint64_t(std::max<std::size_t>(sz.r, 1)) * value;
  bytes += ((std::uint64_t(2) << levels) - 1) * sizeof(float);  // cone angles
  for (std::size_t t : sz.t) bytes += 4 * std::uint64_t(t) * value;
  for (int n = 0; n < 3; ++n)  // the ray pattern tables
    for (int k = 0; k <= (1 << n); ++k)
      bytes += 2 * sizeof(std::int32_t) + hrc::traced_cells(n, k).size() * 4 * sizeof(std::int32_t);
  return bytes;
}

std::uint64_t hrc_largest_buffer(int W, int H, Storage storage) {
  const hrc::Sizes sz = hrc::plan(W, H);
  const std::uint64_t value = storage == Storage::f16 ? 2 : 4;
  std::uint64_t largest = std::max(std::uint64_t(W) * H * 6 * sizeof(float),    // world
                                   6 * std::uint64_t(sz.pad) * sizeof(float));  // view
  largest = std::max(largest, 3 * std::uint64_t(sz.r) * value);
  for (std::size_t t : sz.t) largest = std::max(largest, 4 * std::uint64_t(t) * value);
  return largest;
}

Status record_hrc(Cache& cache, Batch& batch, int W, int H, Buffer& step, Buffer& emission,
                  const std::vector<std::uint32_t>& fan, const Rgb& env, const HrcOptions& o,
                  Buffer& fluence_out) {
  const bool f16 = o.storage == Storage::f16;
  if (f16 && !cache.context().info().storage_f16)
    return Error{"`device` gpu: " + cache.context().info().name +
                 " cannot store 16-bit floats (storageBuffer16BitAccess); drop `hrc.storage` f16"};
  const std::size_t value = f16 ? 2 : 4;  // bytes of one stored T or R value
  const int pad = hrc::kPad;
  const std::uint32_t cells = std::uint32_t(std::size_t(W) * H);
  // The CPU solve's sizes for both view orientations.
  const hrc::Sizes sz = hrc::plan(W, H);
  const hrc::View* views = sz.views;
  const int levels = int(sz.t.size()) - 1;
  const std::vector<std::size_t>& t_size = sz.t;
  const std::size_t r_size = std::max<std::size_t>(sz.r, 1), view_cells = sz.pad;

  struct K {
    const char* name;
    std::span<const std::uint32_t> spirv;
    int buffers;
    std::uint32_t push;
  };
  const K specs[] = {
      {"hrc_world", shaders::hrc_world(), 3, 16},
      {"hrc_view", shaders::hrc_view(), 2, 36},
      {f16 ? "hrc_trace f16" : "hrc_trace", shaders::hrc_trace(f16), 4, 28},
      {f16 ? "hrc_merge_up f16" : "hrc_merge_up", shaders::hrc_merge_up(f16), 2, 20},
      {f16 ? "hrc_merge_down f16" : "hrc_merge_down", shaders::hrc_merge_down(f16), 5, 40},
      {f16 ? "hrc_gather f16" : "hrc_gather", shaders::hrc_gather(f16), 4, 68},
      {f16 ? "hrc_fan f16" : "hrc_fan", shaders::hrc_fan(f16), 6, 40},
      {"hrc_fan_clear", shaders::hrc_fan_clear(), 1, 4}};
  const Kernel* k[std::size(specs)];
  for (std::size_t i = 0; i < std::size(specs); ++i) {
    Expected<const Kernel*> kernel =
        cache.kernel(specs[i].name, specs[i].spirv, specs[i].buffers, specs[i].push);
    if (!kernel) return kernel.error();
    k[i] = *kernel;
  }
  auto make = [&](const std::string& role, std::size_t values, std::size_t bytes = 4) {
    return cache.buffer(kHrc, "hrc " + role, std::max<std::size_t>(values, 1) * bytes);
  };
  Expected<Buffer*> world = make("world", 6 * std::size_t(cells)),
                    view = make("view", 6 * view_cells), r0 = make("r0", 3 * r_size, value),
                    r1 = make("r1", 3 * r_size, value);
  for (const Expected<Buffer*>* b : {&world, &view, &r0, &r1})
    if (!*b) return b->error();
  // HrcOptions::wall_fan: the cells the fan gathers (hrc::fan_cells, written here from the
  // host), and their light, -1 at the other cells.
  Buffer *fan_cells = nullptr, *fan_light = nullptr;
  if (hrc::runs_fan(W, H, o)) {
    if (fan.size() != hrc::fan_budget(W, H, o))
      return Error{"hrc: the fan's cells do not match the grid and options"};
    Expected<Buffer*> c = cache.buffer(kHrc, "hrc fan cells", fan.size() * 4, Memory::host);
    Expected<Buffer*> l = make("fan light", 3 * std::size_t(cells));
    if (!c) return c.error();
    if (!l) return l.error();
    fan_cells = *c, fan_light = *l;
    std::copy(fan.begin(), fan.end(), fan_cells->as<std::uint32_t>());
  }
  Buffer* fluence = &fluence_out;
  if (hrc::blurs_whole_fluence(o)) {  // the gather writes a buffer of its own, the blur the output
    Expected<Buffer*> f = cache.buffer(kHrcBlur, "hrc fluence", 3 * std::size_t(cells) * 4);
    if (!f) return f.error();
    fluence = *f;
  }
  std::vector<Buffer*> t;
  for (std::size_t n = 0; n < t_size.size(); ++n) {
    Expected<Buffer*> b = make(std::string("t ").append(std::to_string(n)), 4 * t_size[n], value);
    if (!b) return b.error();
    t.push_back(*b);
  }
  // Tables: the ray patterns of T_0..T_2 (cells du, dv, length, squared, and per k a range of
  // them) and the cone angles.
  Buffer* pattern[3];
  Buffer* range[3];
  for (int n = 0; n < 3; ++n) {
    std::vector<std::int32_t> cells_of, ranges_of;
    for (int kk = 0; kk <= (1 << n); ++kk) {
      const std::vector<hrc::TracedCell> pc = hrc::traced_cells(n, kk);
      ranges_of.push_back(std::int32_t(cells_of.size() / 4));
      ranges_of.push_back(std::int32_t(pc.size()));
      // A corner: length -1 (Corners::half) or -2 (Corners::walls), then its side.
      for (const hrc::TracedCell& tc : pc) {
        cells_of.push_back(tc.du);
        cells_of.push_back(tc.dv);
        cells_of.push_back(tc.corner == 0 ? tc.length : o.corners == Corners::walls ? -2 : -1);
        cells_of.push_back(tc.corner != 0 ? tc.corner : tc.squared ? 1 : 0);
      }
    }
    Expected<Buffer*> pb =
        cache.table(batch, kHrc, "hrc pattern " + std::to_string(n) + " " + to_string(o.corners),
                    cells_of.data(), cells_of.size() * 4);
    if (!pb) return pb.error();
    Expected<Buffer*> rb = cache.table(batch, kHrc, "hrc range " + std::to_string(n),
                                       ranges_of.data(), ranges_of.size() * 4);
    if (!rb) return rb.error();
    pattern[n] = *pb;
    range[n] = *rb;
  }
  std::vector<float> ang((std::size_t(2) << levels) - 1);
  for (int lv = 0; lv <= levels; ++lv)
    for (int a = 0; a < (1 << lv); ++a)
      ang[std::size_t((1 << lv) - 1 + a)] = hrc::cone_angle(lv, a);
  Expected<Buffer*> angles = cache.table(batch, kHrc, "hrc angles", ang.data(), ang.size() * 4);
  if (!angles) return angles.error();

  auto groups = [](std::size_t n, std::uint32_t size) {
    return std::uint32_t((n + size - 1) / size);
  };
  const float* len = hrc::kLengths;
  {
    struct {
      std::uint32_t cells;
      float l0, l1, l2;
    } push{cells, len[0], len[1], len[2]};
    Buffer* b[] = {&emission, &step, *world};
    batch.mark("views");
    const Groups g = groups_1d(cells, 256, cache.context().info());
    batch.dispatch(*k[0], b, &push, g.x, g.y);
  }
  if (fan_cells) {
    batch.mark("fan");
    Buffer* b[] = {fan_light};
    const std::uint32_t values = 3 * cells;
    const Groups g = groups_1d(values, 256, cache.context().info());
    batch.dispatch(*k[7], b, &values, g.x, g.y);
  }
  for (int d = 0; d < 4; ++d) {
    const hrc::View& v = views[d & 1];
    const hrc::Rotation rot = hrc::rotation(d, W, H);
    const int hp = v.h + 2 * pad;
    {
      const std::int32_t push[9] = {v.w,
                                    v.h,
                                    hp,
                                    pad,
                                    std::int32_t(cells),
                                    std::int32_t(view_cells),
                                    std::int32_t(rot.base),
                                    std::int32_t(rot.su),
                                    std::int32_t(rot.sv)};
      Buffer* b[] = {*world, *view};
      if (d > 0) batch.mark("views");
      batch.dispatch(*k[1], b, push, groups(std::size_t(hp), 64), groups(std::size_t(v.w + pad), 4),
                     6);
    }
    batch.mark("trace T0-T2");
    for (int n = 0; n <= std::min(2, v.levels); ++n) {
      const int P = v.probes(n), rows = ((1 << n) + 1) * P;
      const std::int32_t push[7] = {v.h, hp, pad, n, P, rows, std::int32_t(view_cells)};
      Buffer* b[] = {*view, pattern[n], range[n], t[std::size_t(n)]};
      batch.dispatch(*k[2], b, push, groups(std::size_t(v.h), 64), groups(std::size_t(rows), 4));
    }
    batch.mark("merge up T3-TN");
    for (int n = 3; n <= v.levels; ++n) {
      const int P = v.probes(n - 1), P1 = v.probes(n), rows = ((1 << n) + 1) * P1;
      const std::int32_t push[5] = {v.h, n - 1, P, P1, rows};
      Buffer* b[] = {t[std::size_t(n - 1)], t[std::size_t(n)]};
      batch.dispatch(*k[3], b, push, groups(std::size_t(v.h), 64), groups(std::size_t(rows), 4));
    }
    batch.mark("merge down R");
    Buffer* upper = *r1;  // unread at the top level
    bool top = true;
    const int fan_level = hrc::wall_fan_level(v, o.wall_fan);
    for (int n = v.levels - 1; n >= 0; --n) {
      Buffer* out = upper == *r0 ? *r1 : *r0;
      const int P = v.probes(n), P1 = v.probes(n + 1), rows = (1 << n) * P;
      struct {
        std::int32_t h, n, P, P1, rows, top;
        float er, eg, eb, wd;
      } push{v.h, n, P, P1, rows, top ? 1 : 0, env.r, env.g, env.b, o.even_weight};
      Buffer* b[] = {t[std::size_t(n)], t[std::size_t(n + 1)], upper, *angles, out};
      batch.dispatch(*k[4], b, &push, groups(std::size_t(v.h), 64), groups(std::size_t(rows), 4));
      upper = out;
      top = false;
      if (n != fan_level || !fan_cells) continue;
      batch.mark("fan");
      struct {
        std::int32_t W, H, d, n, P, h;
        float er, eg, eb;
        std::uint32_t count;
      } wp{W, H, d, n, v.probes(n), v.h, env.r, env.g, env.b, std::uint32_t(fan.size())};
      Buffer* wb[] = {&step, &emission, out, *angles, fan_light, fan_cells};
      const Groups g = groups_1d(fan.size(), 64, cache.context().info());
      batch.dispatch(*k[6], wb, &wp, g.x, g.y);
      batch.mark("merge down R");
    }
    batch.mark("views");
    {
      struct {
        std::int32_t w, h, hp, pad;
        std::uint32_t view_cells;
        std::int32_t base, su, sv, first, near;
        float er, eg, eb;
        std::int32_t blur, last;
        float step;
        std::int32_t fan;
      } push{v.w,
             v.h,
             hp,
             pad,
             std::uint32_t(view_cells),
             std::int32_t(rot.base),
             std::int32_t(rot.su),
             std::int32_t(rot.sv),
             d == 0 ? 1 : 0,
             o.near_segment ? 1 : 0,
             env.r,
             env.g,
             env.b,
             hrc::blurs_far_light(o) ? 1 : 0,
             d == 3 ? 1 : 0,
             hrc::kBlurOpacityStep,
             fan_light ? 1 : 0};
      Buffer* b[] = {upper, *view, fluence, fan_light ? fan_light : fluence};
      batch.dispatch(*k[5], b, &push, groups(std::size_t(v.h), 64), groups(std::size_t(v.w), 4));
    }
  }
  if (hrc::blurs_whole_fluence(o))  // the transmittance over half a cell: the world's plane 3
    return record_cross_blur(cache, batch, W, H, **world, 3 * cells, *fluence, fluence_out);
  return {};
}

}  // namespace penumbra::flatland::gpu
