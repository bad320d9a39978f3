#include "gpu/rc.hpp"

#include <algorithm>
#include <cstdint>
#include <string>

#include "gpu/shaders.hpp"

namespace penumbra::gpu {

std::uint64_t rc_device_bytes(const std::vector<rc::Cascade>& plan) {
  std::uint64_t largest = 0, directions = 0;
  for (const rc::Cascade& c : plan) {
    largest = std::max<std::uint64_t>(largest, c.size());
    directions += std::uint64_t(c.directions);
  }
  return 2 * largest * 4 * sizeof(float) + directions * 2 * sizeof(float);
}

std::uint64_t rc_largest_buffer(const std::vector<rc::Cascade>& plan) {
  std::uint64_t largest = 0, directions = 0;
  for (const rc::Cascade& c : plan) {
    largest = std::max<std::uint64_t>(largest, c.size());
    directions += std::uint64_t(c.directions);
  }
  return std::max(largest * 4 * sizeof(float), directions * 2 * sizeof(float));
}

Status record_rc(Cache& cache, Batch& batch, int W, int H, Buffer& step, Buffer& emission,
                 const Rgb& env, const std::vector<rc::Cascade>& plan, const RcOptions& o,
                 Buffer& fluence) {
  if (o.extend) return Error{"GPU RC: interval extension runs on the CPU only"};
  Expected<const Kernel*> merge = cache.kernel("rc_merge", shaders::rc_merge(), 5, 80);
  if (!merge) return merge.error();
  Expected<const Kernel*> gather = cache.kernel("rc_fluence", shaders::rc_fluence(), 4, 28);
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
  Expected<Buffer*> table = cache.table(batch, "rc directions", dirs.data(), dirs.size() * 4);
  if (!table) return table.error();
  Expected<Buffer*> a = cache.buffer("rc cascade a", largest * 16);
  if (!a) return a.error();
  Expected<Buffer*> b = cache.buffer("rc cascade b", largest * 16);
  if (!b) return b.error();

  Buffer* upper = *b;  // unread by the top cascade
  for (int n = int(plan.size()) - 1; n >= 0; --n) {
    const rc::Cascade& c = plan[std::size_t(n)];
    const bool top = n + 1 == int(plan.size());
    const rc::Cascade& u = top ? c : plan[std::size_t(n + 1)];
    Buffer* out = upper == *a ? *b : *a;
    struct {
      std::int32_t w, h, spacing, nx, ny, directions;
      float t_begin, t_end;
      std::uint32_t dir_off;
      std::int32_t u_spacing, u_nx, u_ny;
      float u_t_begin;
      std::uint32_t u_dir_off;
      std::int32_t branching, fix, flags;
      float er, eg, eb;
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
           env.b};
    static_assert(sizeof(push) == 80);
    Buffer* bind[] = {&step, &emission, *table, upper, out};
    batch.mark("cascade " + std::to_string(n));
    const Groups g = groups_1d(c.size(), 64, cache.context().info());
    batch.dispatch(**merge, bind, &push, g.x, g.y);
    upper = out;
  }
  const rc::Cascade& c0 = plan[0];
  struct {
    std::int32_t w, h, spacing, nx, ny, directions;
    float cone;
  } push{
      W, H, c0.spacing, c0.probes_x, c0.probes_y, c0.directions, float(rc::kTwoPi / c0.directions)};
  static_assert(sizeof(push) == 28);
  Buffer* bind[] = {&step, &emission, upper, &fluence};
  batch.mark("fluence");
  batch.dispatch(**gather, bind, &push, (std::uint32_t(W) + 15) / 16, (std::uint32_t(H) + 15) / 16);
  return {};
}

}  // namespace penumbra::gpu
