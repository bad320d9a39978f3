#include "flatland/gpu/rc.hpp"

#include <algorithm>
#include <cstdint>
#include <string>

#include "core/math.hpp"
#include "flatland/gpu/owners.hpp"
#include "flatland/gpu/shaders.hpp"

namespace penumbra::flatland::gpu {

std::uint64_t rc_device_bytes(int W, int H, const std::vector<rc::Cascade>& plan) {
  std::uint64_t largest = 0, directions = 0;
  for (const rc::Cascade& c : plan) {
    largest = std::max<std::uint64_t>(largest, c.size());
    directions += std::uint64_t(c.directions);
  }
  const std::uint64_t weights = std::uint64_t(W) * H * 5 * sizeof(float);  // vec4 and norm
  return 2 * largest * 4 * sizeof(float) + directions * 2 * sizeof(float) + weights;
}

namespace {

constexpr std::uint64_t kInterval = 4 * sizeof(float);  // one stored interval

// Elements of cascade n, and of the cascade above it that direction k's merge reads.
std::uint64_t per_direction(const rc::Cascade& c) {
  return std::uint64_t(c.probes_x) * c.probes_y;
}

}  // namespace

std::uint64_t rc_smallest_binding(const std::vector<rc::Cascade>& plan, int branching) {
  std::uint64_t need = 0, directions = 0;
  for (std::size_t n = 0; n < plan.size(); ++n) {
    need = std::max(need, per_direction(plan[n]) * kInterval);
    if (n + 1 < plan.size())
      need = std::max(need, std::uint64_t(branching) * per_direction(plan[n + 1]) * kInterval);
    directions += std::uint64_t(plan[n].directions);
  }
  return std::max(need, directions * 2 * sizeof(float));
}

Status record_rc(Cache& cache, Batch& batch, int W, int H, Buffer& step, Buffer& emission,
                 const Rgb& env, const std::vector<rc::Cascade>& plan, const RcOptions& o,
                 Buffer& fluence, std::uint64_t binding_limit, std::uint64_t alignment) {
  if (o.extend) return Error{"GPU RC: interval extension runs on the CPU only"};
  Expected<const Kernel*> merge = cache.kernel("rc_merge", shaders::rc_merge(), 5, 100);
  if (!merge) return merge.error();
  Expected<const Kernel*> gather = cache.kernel("rc_fluence", shaders::rc_fluence(), 6, 44);
  if (!gather) return gather.error();

  // Every cascade's directions, one after the other (the CPU's float tables, so the rays match).
  std::vector<float> dirs;
  std::vector<std::uint32_t> offset;
  std::size_t largest = 0;
  for (const rc::Cascade& c : plan) {
    offset.push_back(std::uint32_t(dirs.size() / 2));
    for (int k = 0; k < c.directions; ++k) {
      dirs.push_back(c.dir_x[std::size_t(k)]);
      dirs.push_back(c.dir_y[std::size_t(k)]);
    }
    largest = std::max(largest, c.size());
  }
  Expected<Buffer*> table = cache.table(batch, kRc, "rc directions", dirs.data(), dirs.size() * 4);
  if (!table) return table.error();
  Expected<Buffer*> a =
      cache.buffer(kRc, "rc cascade a", largest * kInterval, Memory::device, true);
  if (!a) return a.error();
  Expected<Buffer*> b =
      cache.buffer(kRc, "rc cascade b", largest * kInterval, Memory::device, true);
  if (!b) return b.error();

  // Directions per dispatch: a slab of cascade n and the upper directions it reads must each
  // fit one binding (offsets aligned down, the shader told where its slab starts).
  const std::uint64_t align =
      std::max({alignment, cache.context().info().offset_alignment, std::uint64_t(1)});
  const std::uint64_t limit = binding_limit > align ? binding_limit - align : 0;
  // The range of `buffer` from element `first` for `count` elements, and where `first` lies in
  // it.
  auto range = [&](Buffer* buffer, std::uint64_t first, std::uint64_t count, std::uint32_t& base) {
    const std::uint64_t start = first * kInterval, aligned = start - start % align;
    base = std::uint32_t((start - aligned) / kInterval);
    const std::uint64_t end = std::min<std::uint64_t>(start + count * kInterval, buffer->bytes());
    return Batch::Range{buffer, std::size_t(aligned), std::size_t(end - aligned)};
  };

  Buffer* upper = *b;  // unread by the top cascade
  for (int n = int(plan.size()) - 1; n >= 0; --n) {
    const rc::Cascade& c = plan[std::size_t(n)];
    const bool top = n + 1 == int(plan.size());
    const rc::Cascade& u = top ? c : plan[std::size_t(n + 1)];
    Buffer* out = upper == *a ? *b : *a;
    const std::uint64_t per = per_direction(c), per_u = top ? 0 : per_direction(u);
    const std::uint64_t widest = std::max(per, std::uint64_t(o.branching) * per_u) * kInterval;
    const int slab = int(std::min<std::uint64_t>(c.directions, limit / widest));
    if (slab < 1)
      return Error{"GPU RC: one direction of cascade " + std::to_string(n) + " needs " +
                   std::to_string(widest) + " bytes, more than one binding holds"};
    batch.mark("cascade " + std::to_string(n));
    for (int k0 = 0; k0 < c.directions; k0 += slab) {
      const int count = std::min(slab, c.directions - k0);
      struct {
        std::int32_t w, h, spacing, nx, ny, directions;
        float t_begin, t_end;
        std::uint32_t dir_off;
        std::int32_t u_spacing, u_nx, u_ny;
        float u_t_begin;
        std::uint32_t u_dir_off;
        std::int32_t branching, fix, flags;
        float er, eg, eb;
        std::int32_t k0, slab, u_k0;
        std::uint32_t out_base, upper_base;
      } push{W,
             H,
             c.spacing,
             c.probes_x,
             c.probes_y,
             c.directions,
             c.t_begin,
             c.t_end,
             offset[std::size_t(n)],
             u.spacing,
             u.probes_x,
             u.probes_y,
             u.t_begin,
             offset[std::size_t(top ? n : n + 1)],
             o.branching,
             o.fix == MergeFix::none      ? 0
             : o.fix == MergeFix::nearest ? 1
                                          : 2,
             (top ? 1 : 0) | (n == 0 ? 2 : 0) | (o.preaverage ? 4 : 0),
             env.r,
             env.g,
             env.b,
             k0,
             count,
             top ? 0 : o.branching * k0,
             0,
             0};
      static_assert(sizeof(push) == 100);
      const Batch::Range out_range =
          range(out, std::uint64_t(k0) * per, count * per, push.out_base);
      const Batch::Range upper_range =
          top ? Batch::Range{upper, 0, kInterval}
              : range(upper, std::uint64_t(o.branching) * k0 * per_u,
                      std::uint64_t(o.branching) * count * per_u, push.upper_base);
      const Batch::Range bind[] = {{&step}, {&emission}, {*table}, upper_range, out_range};
      const Groups g = groups_1d(std::size_t(count) * per, 64, cache.context().info());
      batch.dispatch(**merge, bind, &push, g.x, g.y);
    }
    upper = out;
  }
  const rc::Cascade& c0 = plan[0];
  const std::uint64_t per0 = per_direction(c0);
  const int slab0 = int(std::min<std::uint64_t>(c0.directions, limit / (per0 * kInterval)));
  if (slab0 < 1) return Error{"GPU RC: one direction of cascade 0 is more than one binding holds"};
  // Each cell's visibility weights (a vec4) and normalisation, kept by the first slab for the
  // others.
  const std::size_t cells = std::size_t(W) * H;
  Expected<Buffer*> weights = cache.buffer(kRc, "rc weights", cells * 4 * sizeof(float));
  if (!weights) return weights.error();
  Expected<Buffer*> norms = cache.buffer(kRc, "rc norms", cells * sizeof(float));
  if (!norms) return norms.error();
  batch.mark("fluence");
  for (int k0 = 0; k0 < c0.directions; k0 += slab0) {
    const int count = std::min(slab0, c0.directions - k0);
    struct {
      std::int32_t w, h, spacing, nx, ny, directions;
      float cone;
      std::int32_t k0, first;
      std::uint32_t base;
      std::int32_t keep;
    } push{W,
           H,
           c0.spacing,
           c0.probes_x,
           c0.probes_y,
           count,
           float(kTwoPi / c0.directions),
           k0,
           k0 == 0 ? 1 : 0,
           0,
           slab0 < c0.directions ? 1 : 0};
    static_assert(sizeof(push) == 44);
    const Batch::Range r0 = range(upper, std::uint64_t(k0) * per0, count * per0, push.base);
    const Batch::Range bind[] = {{&step}, {&emission}, r0, {&fluence}, {*weights}, {*norms}};
    batch.dispatch(**gather, bind, &push, (std::uint32_t(W) + 15) / 16,
                   (std::uint32_t(H) + 15) / 16);
  }
  return {};
}

}  // namespace penumbra::flatland::gpu
