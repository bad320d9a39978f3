#include "flatland/gpu/solver.hpp"

#include <algorithm>
#include <cstring>
#include <optional>
#include <string>

#include "core/huge_pages.hpp"
#include "core/timer.hpp"
#include "flatland/gpu/distance.hpp"
#include "flatland/gpu/method.hpp"
#include "flatland/gpu/owners.hpp"
#include "flatland/gpu/shaders.hpp"
#include "gpu/cache.hpp"

namespace penumbra::flatland::gpu {

namespace {

// The scene's arrays as they go to the GPU: floats per cell, and where they are in a Scene.
struct SceneArray {
  const char* role;
  int floats;
  const std::vector<float> Scene::*member;
};
constexpr SceneArray kArrays[] = {{"opacity", 1, &Scene::opacity},
                                  {"emission", 3, &Scene::emission},
                                  {"albedo", 3, &Scene::albedo}};

}  // namespace

struct Solver::Impl {
  explicit Impl(const Context& c) : cache(c) {}
  Cache cache;
  int width = 0, height = 0;
  std::vector<float> held[3];       // what the device's scene arrays hold (empty: nothing yet)
  bool medium_valid = false;        // the step buffer matches held[] ...
  bool medium_jumps = false;        // ... and has distance-field jumps
  std::uint64_t binding_limit = 0;  // 0: the device's
  std::uint64_t alignment = 0;      // of bound offsets, when more than the device's
};

Solver::Solver(std::shared_ptr<Context> context)
    : context_(std::move(context)), impl_(std::make_unique<Impl>(*context_)) {}
Solver::~Solver() = default;

std::uint64_t Solver::device_bytes(const Plan& plan) {
  const std::uint64_t cells = plan.cells();
  // Device-local: the scene arrays, step and fluence (the staging copies and the read-back
  // buffer are host memory).
  std::uint64_t bytes = cells * sizeof(float) * (7 + 1 + 3);
  if (plan.options.bounces > 1) bytes += cells * 3 * sizeof(float);  // the bounce's emission
  return bytes + entry(plan.options.method).gpu->device_bytes(plan);
}

void Solver::limit_binding(std::uint64_t bytes, std::uint64_t alignment) {
  impl_->binding_limit = bytes;
  impl_->alignment = alignment;
}

std::uint64_t Solver::allocated_bytes() const {
  return impl_->cache.allocated(Memory::device);
}

Status Solver::check_memory(const DeviceInfo& info, const Plan& plan) {
  const MethodPasses& m = *entry(plan.options.method).gpu;
  const std::string grid = std::to_string(plan.width) + "x" + std::to_string(plan.height);
  // What must fit one binding (larger would fail halfway through recording), and what helps.
  std::vector<Binding> bindings = {{plan.cells() * 3 * sizeof(float), "the fluence", ""}};
  m.bindings(plan, info, bindings);
  for (const Binding& b : bindings)
    if (info.max_buffer_bytes > 0 && b.bytes > info.max_buffer_bytes)
      return Error{"`device` gpu: on a " + grid + " grid " + b.what + " needs " +
                   std::to_string(b.bytes >> 20) + " MiB in one binding, more than " + info.name +
                   " can bind (" + std::to_string(info.max_buffer_bytes >> 20) +
                   " MiB); use a smaller grid" + b.advice + " or `device` cpu"};
  const std::uint64_t need = device_bytes(plan);
  if (info.device_local_bytes == 0 || need <= info.device_local_bytes) return {};
  return Error{"`device` gpu: a " + grid + " grid needs " + std::to_string(need >> 20) +
               " MiB of GPU memory, more than " + info.name + " has (" +
               std::to_string(info.device_local_bytes >> 20) + " MiB); use a smaller grid" +
               m.grid_advice + " or `device` cpu"};
}

Expected<std::vector<float>> Solver::render(const Scene& scene, const Plan& plan,
                                            std::vector<StageTime>& stages) {
  Stopwatch call;
  Impl& s = *impl_;
  Cache& cache = s.cache;
  cache.uploaded = 0;
  uploaded_ = 0;
  const RenderOptions& o = plan.options;
  const int W = scene.width, H = scene.height;
  const std::size_t cells = std::size_t(W) * H;
  const MethodPasses* method = entry(o.method).gpu;
  if (!method)
    return Error{std::string("GPU: ") + to_string(o.method) + " does not run on the GPU"};
  const DeviceInfo& info = context_->info();
  if (Status st = check_memory(info, plan); !st) return st.error();
  // Buffers of other options (the other method, seeds without the distance field, a bounce's
  // emission, the blur's input) are freed, so what is allocated is what check_memory counted; a
  // new grid frees everything.
  std::vector<Owner> keep;
  if (W == s.width && H == s.height) {
    keep.push_back(kSceneBuffers);
    if (o.bounces > 1) keep.push_back(kBounce);
    method->owners(o, keep);
  } else {
    for (std::vector<float>& h : s.held) h.clear();
    s.width = W, s.height = H;
    s.medium_valid = false;
  }
  cache.release_except(keep);
  // What this render records is on the device only once its batches have run: until then (and
  // for good if it fails anywhere, recording included) nothing is trusted.
  struct Invalidate {
    Impl& s;
    bool armed = true;
    ~Invalidate() {
      if (!armed) return;
      s.cache.forget_tables();
      for (std::vector<float>& h : s.held) h.clear();
      s.medium_valid = false;
    }
  } invalidate{s};

  // Per bounce a batch of its own (a batch holds a bounded number of dispatches); the first
  // also uploads the scene and builds the medium.
  std::vector<std::pair<std::string, std::vector<std::pair<std::string, double>>>> timed;
  auto run = [&](Batch& batch, const std::string& prefix) -> Status {
    Expected<std::vector<std::pair<std::string, double>>> t = batch.run();
    if (!t) return t.error();  // Invalidate forgets what the batch was to upload
    timed.push_back({prefix, std::move(*t)});
    return {};
  };

  Buffer* device[3];
  for (int a = 0; a < 3; ++a) {
    Expected<Buffer*> b =
        cache.buffer(kSceneBuffers, kArrays[a].role, cells * kArrays[a].floats * sizeof(float));
    if (!b) return b.error();
    device[a] = *b;
  }
  Expected<Buffer*> step = cache.buffer(kSceneBuffers, "step", cells * sizeof(float));
  if (!step) return step.error();
  Expected<Buffer*> fluence = cache.buffer(kSceneBuffers, "fluence", cells * 3 * sizeof(float));
  if (!fluence) return fluence.error();
  Buffer* bounce_emission = device[1];  // unused with one bounce
  if (o.bounces > 1) {
    Expected<Buffer*> b = cache.buffer(kBounce, "bounce emission", cells * 3 * sizeof(float));
    if (!b) return b.error();
    bounce_emission = *b;
  }
  Expected<Buffer*> readback =
      cache.buffer(kSceneBuffers, "read back", cells * 3 * sizeof(float), Memory::host);
  if (!readback) return readback.error();

  std::optional<Batch> batch;
  auto begin = [&](std::uint32_t passes) -> Status {
    batch.reset();
    Expected<Batch> b = context_->batch(passes);
    if (!b) return b.error();
    batch.emplace(std::move(*b));
    return {};
  };
  if (Status st = begin(512); !st) return st.error();
  // Upload: the rows from the first to the last that differ from what the device holds.
  int first = H, last = -1;
  bool opacity_changed = false;
  for (int a = 0; a < 3; ++a) {
    const std::vector<float>& now = scene.*kArrays[a].member;
    const std::vector<float>& held = s.held[a];
    const std::size_t row = std::size_t(W) * kArrays[a].floats;
    if (held.size() != now.size()) {
      first = 0, last = H - 1;
      opacity_changed = true;
      break;
    }
    for (int y = 0; y < H; ++y)
      if (std::memcmp(&held[y * row], &now[y * row], row * sizeof(float)) != 0) {
        first = std::min(first, y), last = std::max(last, y);
        opacity_changed |= a == 0;
      }
  }
  if (last >= first) {
    batch->mark("upload");
    for (int a = 0; a < 3; ++a) {
      const std::vector<float>& now = scene.*kArrays[a].member;
      const std::size_t row = std::size_t(W) * kArrays[a].floats;
      Expected<Buffer*> staging =
          cache.buffer(kSceneBuffers, std::string(kArrays[a].role) + " staging",
                       now.size() * sizeof(float), Memory::host);
      if (!staging) return staging.error();
      const std::size_t offset = first * row * sizeof(float);
      const std::size_t bytes = std::size_t(last - first + 1) * row * sizeof(float);
      std::memcpy(static_cast<unsigned char*>((*staging)->data()) + offset,
                  reinterpret_cast<const unsigned char*>(now.data()) + offset, bytes);
      batch->copy(**staging, offset, *device[a], offset, bytes);
      cache.uploaded += bytes;
      // The held copy takes the same rows (all of them after a new grid or a failure).
      std::vector<float>& held = s.held[a];
      if (held.size() != now.size())
        held = now;
      else
        std::memcpy(held.data() + first * row, now.data() + first * row, bytes);
    }
    // The medium (extinction and jumps) depends on opacity alone: new emission or albedo
    // keeps it.
    if (opacity_changed) s.medium_valid = false;
  }
  const bool jumps = method->jumps(o);
  if (!s.medium_valid || s.medium_jumps != jumps) {
    Expected<const Kernel*> medium =
        cache.kernel("medium", shaders::medium(), 2, sizeof(std::uint32_t));
    if (!medium) return medium.error();
    const std::uint32_t n = std::uint32_t(cells);
    Buffer* bind[] = {device[0], *step};
    batch->mark("medium");
    const Groups g = groups_1d(cells, 256, info);
    batch->dispatch(**medium, bind, &n, g.x, g.y);
    if (jumps)
      if (Status st = record_distance_field(cache, *batch, W, H, **step); !st) return st.error();
    s.medium_valid = true;
    s.medium_jumps = jumps;
  }

  GpuSolve solve{cache,
                 plan,
                 **step,
                 scene,
                 scene.environment,
                 **fluence,
                 s.binding_limit ? s.binding_limit : info.max_buffer_bytes,
                 s.alignment,
                 {}};
  if (Status st = method->record(solve, *batch, *device[1]); !st) return st.error();
  std::string prefix;  // of the batch being recorded
  for (int bounce = 2; bounce <= o.bounces; ++bounce) {
    if (Status st = run(*batch, prefix); !st) return st.error();
    if (Status st = begin(512); !st) return st.error();
    prefix = "bounce " + std::to_string(bounce) + " ";
    Expected<const Kernel*> k = cache.kernel("bounce", shaders::bounce(), 4, sizeof(std::uint32_t));
    if (!k) return k.error();
    const std::uint32_t values = std::uint32_t(3 * cells);
    Buffer* bind[] = {device[1], device[2], *fluence, bounce_emission};
    batch->mark("emission");
    const Groups g = groups_1d(3 * cells, 256, info);
    batch->dispatch(**k, bind, &values, g.x, g.y);
    if (Status st = method->record(solve, *batch, *bounce_emission); !st) return st.error();
  }
  if (o.bounces > 1) {  // the read back is not part of the last bounce
    if (Status st = run(*batch, prefix); !st) return st.error();
    if (Status st = begin(4); !st) return st.error();
    prefix.clear();
  }
  batch->mark("read back");
  batch->copy(**fluence, 0, **readback, 0, cells * 3 * sizeof(float));
  if (Status st = run(*batch, prefix); !st) return st.error();
  invalidate.armed = false;
  const float* f = (*readback)->as<float>();
  std::vector<float> result;
  reserve_huge(result, 3 * cells);
  result.assign(f, f + 3 * cells);

  // Stages: each batch's passes, summed by name (HRC repeats its passes per quadrant).
  double in_passes = 0;
  for (const auto& [prefix, passes] : timed) {
    const std::size_t begin = stages.size();
    for (const auto& [name, ms] : passes) {
      in_passes += ms;
      const std::string full = prefix + "gpu " + name;
      auto it = std::find_if(stages.begin() + std::ptrdiff_t(begin), stages.end(),
                             [&](const StageTime& st) { return st.name == full; });
      if (it == stages.end())
        stages.push_back({full, ms});
      else
        it->ms += ms;
    }
  }
  stages.push_back({"setup and transfers", std::max(0.0, call.ms() - in_passes)});
  uploaded_ = cache.uploaded;
  return result;
}

}  // namespace penumbra::flatland::gpu
