#include "spaceland/ssrc/gpu.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "gpu/vulkan.hpp"
#include "io/json_reader.hpp"
#include "spaceland/sky.hpp"

namespace penumbra::spaceland::ssrc {

namespace {

// SPIR-V words written by glslc -mfmt=num (cmake/shaders.cmake).
const std::uint32_t kMarch[] = {
#include "ssrc_march.comp.inc"
};
const std::uint32_t kRefill[] = {
#include "ssrc_refill.comp.inc"
};
const std::uint32_t kProbeMean[] = {
#include "ssrc_probe_mean.comp.inc"
};
const std::uint32_t kShade[] = {
#include "ssrc_shade.comp.inc"
};

using gpu::Batch;
using gpu::Buffer;
using gpu::Memory;

// The kernels' parameters (ssrc/shaders/ssrc.glsl, std430: the same offsets).
struct Global {
  float eye[4], f[4], r[4], u[4];
  float ground[4], horizon[4], zenith[4];
  float width, height, tan_half, spr;
  std::int32_t sectors, bins, per_bin, q0;
  std::int32_t image_w, image_h, pad0, pad1;
  float cos_sector[32], sin_sector[32], bin_weight[32], cos_sum[36], sin_sum[36];
};
static_assert(sizeof(Global) == 832);
struct CascadeParams {
  std::int32_t level, level_w, level_off, most;
  float a, step, stretch, pad;
  std::int32_t top, dirs, nx, spacing;
  std::int32_t probe_off, corner_off, dir_off, up_dirs;
};
static_assert(sizeof(CascadeParams) == 64);

void put(float* out, Vec3 v) {
  out[0] = v.x, out[1] = v.y, out[2] = v.z, out[3] = 0;
}
void put(float* out, Rgb c) {
  out[0] = c.r, out[1] = c.g, out[2] = c.b, out[3] = 0;
}

// A range of floats of a buffer that one dispatch reads or writes.
struct Span {
  std::uint64_t lo = std::numeric_limits<std::uint64_t>::max(), hi = 0;
  bool empty() const { return lo >= hi; }
  void add(std::uint64_t a, std::uint64_t b) { lo = std::min(lo, a), hi = std::max(hi, b); }
};

// Items [first, first + count) of a dispatch, and the floats of the store it writes and reads.
struct Slab {
  std::uint64_t first = 0, count = 0;
  Span out, read;
};

// Items 0..n-1 in slabs, as many a slab as keep its spans (spans(i, out, read) adds item i's)
// within `limit` bytes once their offsets are aligned down to `align`.
template <class Spans>
Expected<std::vector<Slab>> plan_slabs(std::uint64_t n, std::uint64_t limit, std::uint64_t align,
                                       const char* what, Spans&& spans) {
  auto fits = [&](const Span& s) { return s.empty() || (s.hi - s.lo) * 4 + align <= limit; };
  std::vector<Slab> slabs;
  Slab cur;
  for (std::uint64_t i = 0; i < n; ++i) {
    Slab next = cur;
    if (next.count == 0) next.first = i;
    spans(i, next.out, next.read);
    ++next.count;
    if (fits(next.out) && fits(next.read)) {
      cur = next;
      continue;
    }
    if (cur.count == 0)
      return Error{std::string("ssrc on the GPU: one ") + what +
                   " needs more than one binding of " + io::format_mib(limit) + " holds"};
    slabs.push_back(cur);
    cur = Slab{};
    --i;  // this item starts the next slab
  }
  if (cur.count > 0) slabs.push_back(cur);
  return slabs;
}

// The part of `buffer` holding span s, its offset aligned down; `origin`: its first float.
Batch::Range bind(const Buffer& buffer, const Span& s, std::uint64_t align, std::uint32_t& origin) {
  const std::uint64_t start = s.lo * 4, aligned = start - start % align;
  origin = std::uint32_t(aligned / 4);
  return Batch::Range{&buffer, std::size_t(aligned), std::size_t(s.hi * 4 - aligned)};
}

// The corner weights as the kernels read them: 4 indices, then 4 weights' bits, per point (all
// weights 0: none, as when the CPU's upper_corners or gather_corners returns false).
struct CornerTable {
  std::vector<std::uint32_t> words;
  std::atomic<bool> too_many{false};  // more than 4 corners (only the min-max merge makes them)
  void set(std::size_t at, const cascade::Corners& c) {
    if (c.n > 4) {
      too_many = true;
      return;
    }
    for (int j = 0; j < c.n; ++j) {
      words[8 * at + std::size_t(j)] = std::uint32_t(c.index[std::size_t(j)]);
      std::memcpy(&words[8 * at + 4 + std::size_t(j)], &c.w[std::size_t(j)], sizeof(float));
    }
  }
};

// Device buffers filled through host staging buffers, copied in one batch.
struct Uploads {
  const gpu::Context& context;
  std::uint64_t limit;  // whole-bound buffers may not pass it
  std::vector<Buffer> staging;
  std::uint64_t bytes = 0;

  Expected<Buffer> upload(Batch& batch, const void* data, std::size_t bytes_in, const char* what) {
    // At least 16 bytes bound (the padding zeroed); only the caller's bytes are read.
    const std::size_t size = std::max<std::size_t>(bytes_in, 16);
    if (size > limit)
      return Error{std::string("ssrc on the GPU: ") + what + " take " + io::format_mib(size) +
                   ", more than one binding of " + io::format_mib(limit) +
                   " holds; render a smaller image or use --device cpu"};
    Expected<Buffer> host = context.buffer(size, Memory::host);
    if (!host) return host.error();
    if (data) {
      std::memcpy(host->data(), data, bytes_in);
      if (size > bytes_in)
        std::memset(static_cast<char*>(host->data()) + bytes_in, 0, size - bytes_in);
    }
    Expected<Buffer> dev = context.buffer(size, Memory::device);
    if (!dev) return dev.error();
    batch.copy(*host, 0, *dev, 0, size);
    staging.push_back(std::move(*host));
    bytes += size;
    return dev;
  }
  template <class T>
  Expected<Buffer> upload(Batch& batch, const std::vector<T>& v, const char* what) {
    return upload(batch, v.empty() ? nullptr : v.data(), v.size() * sizeof(T), what);
  }
};

}  // namespace

std::uint64_t gpu_bytes(const Layout& l, const SsrcOptions& o) {
  const std::uint64_t pixels = std::uint64_t(l.tiles.width) * std::uint64_t(l.tiles.height);
  // The pyramid's texels: level 0 and the halvings above it, each rounded up.
  std::uint64_t texels = 0;
  for (std::uint64_t w = std::uint64_t(l.tiles.width), h = std::uint64_t(l.tiles.height);;
       w = (w + 1) / 2, h = (h + 1) / 2) {
    texels += w * h;
    if (w == 1 && h == 1) break;
  }
  std::uint64_t probes = 0, largest = 0;
  for (int i = 0; i < l.count(); ++i) {
    probes += l.probes(i);
    largest = std::max(largest, l.values(i));
  }
  const std::uint64_t f = sizeof(float);
  // Uploaded (a host copy, its staging copy, the device's): texel records, counts, radiance;
  // per pixel light and albedo, the view and normal (--gather pixel), the gather's corners; per
  // probe its record and its merge corners.
  const std::uint64_t uploaded = texels * (std::uint64_t(kTexelFloats) + 1 + 3) * f +
                                 pixels * (6 + (o.gather == SpwiGather::pixel ? 6 : 0) + 8) * f +
                                 probes * 16 * f;
  return 3 * uploaded + 2 * largest * 3 * f + l.probes(0) * 4 * f + 2 * pixels * 3 * f;
}

Status check_gpu_options(const SsrcOptions& o) {
  if (o.offscreen == SsrcOffscreen::world)
    return Error{
        "`device` gpu: `ssrc.offscreen` world traces rays through the scene, on the CPU only; "
        "use `ssrc.offscreen` sky or `device` cpu"};
  if (o.merge == SpwiMerge::fix)
    return Error{
        "`device` gpu: `ssrc.merge` fix is on the CPU only; use another `ssrc.merge` or "
        "`device` cpu"};
  return {};
}

Expected<ImageRgb> render_gpu(const SolveContext& ctx, const SsrcOptions& o,
                              const Prepared& prepared, SolveReport& report) {
  return render_gpu(ctx, o, prepared, report, 0);
}

Expected<ImageRgb> render_gpu(const SolveContext& ctx, const SsrcOptions& o, const Prepared& pr,
                              SolveReport& report, std::uint64_t binding_bytes) {
  if (Status s = check_gpu_options(o); !s) return s.error();
  Stopwatch watch;
  Expected<std::shared_ptr<gpu::Context>> opened = gpu::Context::create(true);
  if (!opened) return opened.error();
  const gpu::Context& device = **opened;
  const gpu::DeviceInfo& info = device.info();
  report.stages.push_back({"GPU device", watch.ms()});

  const Layout& l = pr.layout;
  const GBuffer& g = ctx.g;
  const int count = l.count();
  const std::size_t pixels = std::size_t(g.width) * std::size_t(g.height);
  const std::uint64_t limit =
      binding_bytes > 0 ? std::min(binding_bytes, info.max_buffer_bytes) : info.max_buffer_bytes;
  const std::uint64_t align = std::max<std::uint64_t>(info.offset_alignment, 4);
  const int bins = l.bins;

  // ---- What the kernels read, gathered on the CPU ----
  watch.restart();
  Global global{};
  put(global.eye, pr.eye);
  put(global.f, pr.forward);
  put(global.r, pr.right);
  put(global.u, pr.up);
  put(global.ground, ctx.scene.sky.ground);
  put(global.horizon, ctx.scene.sky.horizon);
  put(global.zenith, ctx.scene.sky.zenith);
  global.width = float(g.width);
  global.height = float(g.height);
  global.tan_half = pr.tan_half;
  global.spr = float(l.sectors / kPi);  // as ssrc.cpp's sectors_per_radian
  global.sectors = l.sectors;
  global.bins = bins;
  global.per_bin = l.sectors / bins;
  global.q0 = l.q0;
  global.image_w = g.width;
  global.image_h = g.height;
  for (int k = 0; k < l.sectors; ++k) {
    global.cos_sector[k] = pr.cos_sector[std::size_t(k)];
    global.sin_sector[k] = pr.sin_sector[std::size_t(k)];
    global.bin_weight[k] = pr.bin_weight[std::size_t(k)];
  }
  for (int k = 0; k <= l.sectors; ++k) {
    global.cos_sum[k] = pr.cos_sum[std::size_t(k)];
    global.sin_sum[k] = pr.sin_sum[std::size_t(k)];
  }

  // The pyramid's levels one after the other: the march's texel records, the hits' counts and
  // the radiance (level 0: what the first bounce marches; the refill fills the levels above).
  std::vector<std::uint64_t> level_off;
  std::uint64_t texels = 0;
  for (const Prepared::Level& lv : pr.levels) {
    level_off.push_back(texels);
    texels += std::uint64_t(lv.width) * std::uint64_t(lv.height);
  }
  std::vector<float> texel_data(kTexelFloats * texels), count_data(texels),
      radiance(3 * texels, 0.0f);
  for (std::size_t lv = 0; lv < pr.levels.size(); ++lv) {
    const std::size_t at = std::size_t(level_off[lv]);
    std::memcpy(texel_data.data() + kTexelFloats * at, pr.levels[lv].texels.data(),
                pr.levels[lv].texels.size());
    std::copy(pr.levels[lv].count.begin(), pr.levels[lv].count.end(), count_data.begin() + at);
  }
  std::memcpy(radiance.data(), pr.radiance.data(), pixels * sizeof(Rgb));

  // Per cascade: its parameters, screen directions (the CPU's floats), probes and the upper
  // probes each merges with.
  std::vector<CascadeParams> params(static_cast<std::size_t>(count));
  std::vector<float> dirs, probes;
  std::uint64_t probe_total = 0, largest = 0;
  for (int i = 0; i < count; ++i) {
    const int level = l.level(i);
    const double step = double(1 << level), a = l.start(i);
    CascadeParams& c = params[std::size_t(i)];
    c.level = level;
    c.level_w = pr.levels[std::size_t(level)].width;
    c.level_off = std::int32_t(level_off[std::size_t(level)]);
    c.most = l.samples(i);
    c.a = float(a);
    c.step = float(step);
    c.stretch = float(step);
    c.top = l.top(i) ? 1 : 0;
    c.dirs = l.directions(i);
    c.nx = l.tiles.nx[std::size_t(i)];
    c.spacing = l.tiles.spacing(i);
    c.probe_off = std::int32_t(probe_total);
    c.corner_off = c.probe_off;
    c.dir_off = std::int32_t(dirs.size() / 2);
    c.up_dirs = l.top(i) ? 0 : l.directions(i + 1);
    for (int d = 0; d < c.dirs; ++d) {
      const double phi = l.phi(i, d);
      dirs.push_back(float(std::cos(phi)));
      dirs.push_back(float(std::sin(phi)));
    }
    for (const spwi::Probe& p : pr.probes[std::size_t(i)])
      probes.insert(probes.end(),
                    {p.p.x, p.p.y, p.p.z, p.valid ? 1.0f : 0.0f, p.n.x, p.n.y, p.n.z, p.depth});
    probe_total += pr.probes[std::size_t(i)].size();
    largest = std::max(largest, l.values(i));
  }
  report.stages.push_back({"GPU tables", watch.ms()});

  watch.restart();
  CornerTable upper;
  upper.words.assign(8 * std::size_t(probe_total), 0);
  for (int i = 0; i + 1 < count; ++i) {
    const std::vector<spwi::Probe>& ps = pr.probes[std::size_t(i)];
    const int nx = l.tiles.nx[std::size_t(i)], spacing = l.tiles.spacing(i);
    const std::size_t off = std::size_t(params[std::size_t(i)].corner_off);
    parallel_for(l.tiles.ny[std::size_t(i)], [&](int py) {
      for (int px = 0; px < nx; ++px) {
        const std::size_t q = std::size_t(py) * std::size_t(nx) + std::size_t(px);
        cascade::Corners c;
        if (ps[q].valid && spwi::upper_corners(l.tiles, i + 1, spwi::tile_centre(px, spacing),
                                               spwi::tile_centre(py, spacing), ps[q],
                                               pr.probes[std::size_t(i + 1)], pr.probe_options, c))
          upper.set(off + q, c);
      }
    });
  }
  CornerTable gather;
  gather.words.assign(8 * pixels, 0);
  std::vector<float> light(6 * pixels, 0.0f), view;
  const bool per_pixel = o.gather == SpwiGather::pixel;
  if (per_pixel) view.assign(6 * pixels, 0.0f);
  parallel_for(g.height, [&](int y) {
    for (int x = 0; x < g.width; ++x) {
      const std::size_t k = std::size_t(y) * std::size_t(g.width) + std::size_t(x);
      if (!g.found[k]) continue;
      const Hit& h = g.hits[k];
      cascade::Corners c;
      if (spwi::gather_corners(l.tiles, 0, x, y, g.linear_depth(k), h.geometric_normal,
                               pr.probes[0], pr.probe_options, c))
        gather.set(k, c);
      std::memcpy(&light[6 * k], &pr.direct[k], sizeof(Rgb));
      std::memcpy(&light[6 * k + 3], &pr.albedo[k], sizeof(Rgb));
      if (per_pixel) {
        const Vec3 v = g.directions[k] * -1.0f, n = h.shading_normal;
        view[6 * k] = v.x, view[6 * k + 1] = v.y, view[6 * k + 2] = v.z;
        view[6 * k + 3] = n.x, view[6 * k + 4] = n.y, view[6 * k + 5] = n.z;
      }
    }
  });
  if (upper.too_many || gather.too_many)
    return Error{"ssrc on the GPU: a merge with more than 4 corners (only min-max makes them)"};
  report.stages.push_back({"corners", watch.ms()});

  // ---- Upload ----
  watch.restart();
  Expected<gpu::Kernel> march = device.kernel("ssrc_march", kMarch, 8, 32);
  if (!march) return march.error();
  Expected<gpu::Kernel> refill = device.kernel("ssrc_refill", kRefill, 2, 24);
  if (!refill) return refill.error();
  Expected<gpu::Kernel> probe_mean = device.kernel("ssrc_probe_mean", kProbeMean, 5, 12);
  if (!probe_mean) return probe_mean.error();
  Expected<gpu::Kernel> shade = device.kernel("ssrc_shade", kShade, 9, 16);
  if (!shade) return shade.error();

  Expected<Batch> up = device.batch();
  if (!up) return up.error();
  Uploads u{device, limit, {}, 0};
  std::vector<unsigned char> param_bytes(sizeof(Global) + params.size() * sizeof(CascadeParams));
  std::memcpy(param_bytes.data(), &global, sizeof(Global));
  std::memcpy(param_bytes.data() + sizeof(Global), params.data(),
              params.size() * sizeof(CascadeParams));
  Expected<Buffer> b_params = u.upload(*up, param_bytes, "the parameters");
  if (!b_params) return b_params.error();
  Expected<Buffer> b_dirs = u.upload(*up, dirs, "the directions");
  if (!b_dirs) return b_dirs.error();
  Expected<Buffer> b_probes = u.upload(*up, probes, "the probes");
  if (!b_probes) return b_probes.error();
  Expected<Buffer> b_upper = u.upload(*up, upper.words, "the merge's corners");
  if (!b_upper) return b_upper.error();
  Expected<Buffer> b_texels = u.upload(*up, texel_data, "the pyramid's texel records");
  if (!b_texels) return b_texels.error();
  Expected<Buffer> b_count = u.upload(*up, count_data, "the pyramid's hit counts");
  if (!b_count) return b_count.error();
  Expected<Buffer> b_radiance = u.upload(*up, radiance, "the pyramid's radiance");
  if (!b_radiance) return b_radiance.error();
  Expected<Buffer> b_gather = u.upload(*up, gather.words, "the gather's corners");
  if (!b_gather) return b_gather.error();
  Expected<Buffer> b_light = u.upload(*up, light, "the direct light and albedo");
  if (!b_light) return b_light.error();
  Expected<Buffer> b_view = u.upload(*up, view, "the pixels' view vectors and normals");
  if (!b_view) return b_view.error();
  if (Expected<std::vector<std::pair<std::string, double>>> t = up->run(); !t) return t.error();
  u.staging.clear();
  // The host's copies are on the device now (the corners stay: they plan the slabs).
  for (std::vector<float>* v : {&texel_data, &count_data, &radiance, &light, &view})
    std::vector<float>().swap(*v);
  // Written on the device only: the two cascades' stores (ping-pong, bound in slabs), the
  // probes' means (--gather probe) and the image.
  const std::size_t store_bytes = std::size_t(largest) * 3 * sizeof(float);
  Expected<Buffer> store_a = device.buffer(store_bytes, Memory::device, true);
  if (!store_a) return store_a.error();
  Expected<Buffer> store_b = device.buffer(store_bytes, Memory::device, true);
  if (!store_b) return store_b.error();
  const std::size_t probes0 = pr.probes[0].size();
  if (probes0 * 16 > limit || pixels * 12 > limit)
    return Error{"ssrc on the GPU: the image takes more than one binding of " +
                 io::format_mib(limit) + " holds; render a smaller image or use --device cpu"};
  Expected<Buffer> means = device.buffer(std::max<std::size_t>(probes0 * 16, 16), Memory::device);
  if (!means) return means.error();
  Expected<Buffer> image = device.buffer(pixels * 12, Memory::device);
  if (!image) return image.error();
  Expected<Buffer> readback = device.buffer(pixels * 12, Memory::host);
  if (!readback) return readback.error();
  report.memory_bytes += u.bytes + 2 * store_bytes + probes0 * 16 + 2 * pixels * 12;
  report.stages.push_back({"upload", watch.ms()});

  // Slabs: per cascade, of probes (each writes its directions, reads its upper corners'); of
  // cascade 0's probes for their means; of pixels for the gather.
  std::vector<std::vector<Slab>> march_slabs(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    const std::uint64_t per = std::uint64_t(l.directions(i)) * std::uint64_t(bins) * 3;
    const std::uint64_t per_up =
        l.top(i) ? 0 : std::uint64_t(l.directions(i + 1)) * std::uint64_t(bins) * 3;
    const std::size_t off = std::size_t(params[std::size_t(i)].corner_off);
    Expected<std::vector<Slab>> s =
        plan_slabs(l.probes(i), limit, align, "probe's directions",
                   [&](std::uint64_t q, Span& out, Span& read) {
                     out.add(q * per, (q + 1) * per);
                     for (int j = 0; j < 4; ++j) {
                       float w;
                       std::memcpy(&w, &upper.words[8 * (off + q) + 4 + std::size_t(j)], sizeof w);
                       const std::uint64_t at = upper.words[8 * (off + q) + std::size_t(j)];
                       if (w > 0) read.add(at * per_up, (at + 1) * per_up);
                     }
                   });
    if (!s) return s.error();
    march_slabs[std::size_t(i)] = std::move(*s);
  }
  const std::uint64_t per0 = std::uint64_t(l.q0) * std::uint64_t(bins) * 3;
  Expected<std::vector<Slab>> mean_slabs =
      plan_slabs(probes0, limit, align, "probe's store",
                 [&](std::uint64_t q, Span&, Span& read) { read.add(q * per0, (q + 1) * per0); });
  if (!mean_slabs) return mean_slabs.error();
  Expected<std::vector<Slab>> shade_slabs =
      plan_slabs(pixels, limit, align, "pixel's probes", [&](std::uint64_t k, Span&, Span& read) {
        if (!per_pixel) return;
        for (int j = 0; j < 4; ++j) {
          float w;
          std::memcpy(&w, &gather.words[8 * k + 4 + std::size_t(j)], sizeof w);
          const std::uint64_t at = gather.words[8 * k + std::size_t(j)];
          if (w > 0) read.add(at * per0, (at + 1) * per0);
        }
      });
  if (!shade_slabs) return shade_slabs.error();

  // ---- Per bounce: the pyramid's radiance, the cascades top down, the gather ----
  const float on_plane2 = kOnPlane * kOnPlane;
  Buffer* const dummy = &*b_params;  // bound where a kernel reads nothing (never read)
  const Batch::Range dummy_range{dummy, 0, 16};
  for (int bounce = 1; bounce <= ctx.bounces; ++bounce) {
    const std::string of = ctx.bounces > 1 ? " (bounce " + std::to_string(bounce) + ")" : "";
    Expected<Batch> batch = device.batch(std::uint32_t(count + 4));
    if (!batch) return batch.error();
    batch->mark("radiance" + of);
    if (bounce > 1) batch->copy(*image, 0, *b_radiance, 0, pixels * 12);
    for (std::size_t lv = 1; lv < pr.levels.size(); ++lv) {
      const Prepared::Level &below = pr.levels[lv - 1], &at = pr.levels[lv];
      const std::int32_t push[6] = {std::int32_t(level_off[lv - 1]), below.width, below.height,
                                    std::int32_t(level_off[lv]),     at.width,    at.height};
      Buffer* bufs[] = {&*b_count, &*b_radiance};
      batch->dispatch(*refill, bufs, push, (std::uint32_t(at.width) + 15) / 16,
                      (std::uint32_t(at.height) + 15) / 16);
    }
    Buffer* upper_store = &*store_b;
    for (int i = count - 1; i >= 0; --i) {
      Buffer* out = upper_store == &*store_a ? &*store_b : &*store_a;
      batch->mark("cascade " + std::to_string(i) + of);
      const std::uint64_t dirs_i = std::uint64_t(l.directions(i));
      for (const Slab& s : march_slabs[std::size_t(i)]) {
        struct {
          std::int32_t cascade;
          std::uint32_t first, count, out_origin, up_origin;
          float on_plane2, tiny, pad;
        } push{i,
               std::uint32_t(s.first * dirs_i),
               std::uint32_t(s.count * dirs_i),
               0,
               0,
               on_plane2,
               kParallel,
               0};
        static_assert(sizeof(push) == 32);
        const Batch::Range out_range = bind(*out, s.out, align, push.out_origin);
        const Batch::Range up_range =
            s.read.empty() ? dummy_range : bind(*upper_store, s.read, align, push.up_origin);
        const Batch::Range ranges[] = {{&*b_params}, {&*b_dirs},     {&*b_probes}, {&*b_upper},
                                       {&*b_texels}, {&*b_radiance}, up_range,     out_range};
        const gpu::Groups gr = gpu::groups_1d(std::size_t(push.count), 64, info);
        batch->dispatch(*march, ranges, &push, gr.x, gr.y);
      }
      upper_store = out;
    }
    batch->mark("gather" + of);
    if (!per_pixel)
      for (const Slab& s : *mean_slabs) {
        struct {
          std::uint32_t first, count, store_origin;
        } push{std::uint32_t(s.first), std::uint32_t(s.count), 0};
        const Batch::Range store_range = bind(*upper_store, s.read, align, push.store_origin);
        const Batch::Range ranges[] = {
            {&*b_params}, {&*b_dirs}, {&*b_probes}, store_range, {&*means}};
        const gpu::Groups gr = gpu::groups_1d(s.count, 64, info);
        batch->dispatch(*probe_mean, ranges, &push, gr.x, gr.y);
      }
    for (const Slab& s : *shade_slabs) {
      struct {
        std::uint32_t first, count, store_origin;
        std::int32_t per_pixel;
      } push{std::uint32_t(s.first), std::uint32_t(s.count), 0, per_pixel ? 1 : 0};
      const Batch::Range store_range =
          s.read.empty() ? dummy_range : bind(*upper_store, s.read, align, push.store_origin);
      const Batch::Range ranges[] = {{&*b_params}, {&*b_dirs},  {&*b_gather},
                                     {&*b_count},  {&*b_light}, {&*b_view},
                                     store_range,  {&*means},   {&*image}};
      const gpu::Groups gr = gpu::groups_1d(s.count, 64, info);
      batch->dispatch(*shade, ranges, &push, gr.x, gr.y);
    }
    watch.restart();
    Expected<std::vector<std::pair<std::string, double>>> times = batch->run();
    if (!times) return times.error();
    if (times->empty())  // no timestamps on this queue: the bounce's time as the host saw it
      report.stages.push_back({"cascades and gather" + of, watch.ms()});
    for (auto& [name, ms] : *times) report.stages.push_back({std::move(name), ms});
  }

  // ---- Readback; the sky where a pixel sees none ----
  watch.restart();
  Expected<Batch> back = device.batch();
  if (!back) return back.error();
  back->copy(*image, 0, *readback, 0, pixels * 12);
  if (Expected<std::vector<std::pair<std::string, double>>> t = back->run(); !t) return t.error();
  std::vector<float> px(3 * pixels);
  std::memcpy(px.data(), readback->data(), pixels * 12);
  ImageRgb img(g.width, g.height, std::move(px));
  const Background bg(ctx.scene);
  for (std::size_t k = 0; k < pixels; ++k)
    if (!g.found[k])
      img.set(int(k % std::size_t(g.width)), int(k / std::size_t(g.width)), bg(g.directions[k]));
  report.stages.push_back({"readback", watch.ms()});
  return img;
}

}  // namespace penumbra::spaceland::ssrc
