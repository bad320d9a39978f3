// render(): the library's entry point for running a method on a scene.
#include "penumbra/flatland/render.hpp"

#include <tbb/task_arena.h>

#include <cmath>
#include <limits>
#include <string>

#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "flatland/gpu/solver.hpp"
#include "flatland/hrc/hrc.hpp"
#include "flatland/medium.hpp"
#include "flatland/pt/pt.hpp"
#include "flatland/rc/rc.hpp"
#include "gpu/vulkan.hpp"

namespace penumbra::flatland {

Status check_options(int width, int height, const RenderOptions& o) {
  auto bad = [](const std::string& what) { return Status(Error{what}); };
  if (width < 1 || height < 1 || width > kMaxGridSide || height > kMaxGridSide)
    return bad("grid: expected 1..16384 cells a side, found " + std::to_string(width) + "x" +
               std::to_string(height));
  if (o.bounces < 1 || o.bounces > 64)
    return bad("bounces: expected 1..64, found " + std::to_string(o.bounces));
  if (o.threads < 0) return bad("threads: expected >= 0, found " + std::to_string(o.threads));
  if (o.device == Device::gpu) {
    if (o.method == Method::pt)
      return bad("device gpu: the path tracer runs on the CPU only (docs/GPU.md)");
    if (o.method == Method::rc && o.rc.extend)
      return bad("device gpu: interval extension runs on the CPU only; drop --extend");
  }
  if (o.method == Method::pt) {
    const PtOptions& pt = o.pt;
    if (pt.spp < 0) return bad("spp: expected >= 0, found " + std::to_string(pt.spp));
    if (!(pt.seconds >= 0) || !std::isfinite(pt.seconds))
      return bad("time: expected a number of seconds >= 0, found " + std::to_string(pt.seconds));
    if (pt.spp == 0 && pt.seconds == 0) return bad("spp: 0 (no limit) needs a time limit (--time)");
    return {};
  }
  if (o.method == Method::hrc) return {};
  const RcOptions& rc = o.rc;
  if (rc.probe_spacing < 1 || rc.probe_spacing > 64)
    return bad("probe spacing: expected 1..64 cells, found " + std::to_string(rc.probe_spacing));
  if (rc.directions < 1 || rc.directions > 64)
    return bad("directions: expected 1..64, found " + std::to_string(rc.directions));
  if (rc.branching != 2 && rc.branching != 4)
    return bad("branching: expected 2 or 4, found " + std::to_string(rc.branching));
  if (!(rc.interval > 0.0f) || !std::isfinite(rc.interval))
    return bad("interval t0: expected a number > 0, found " + std::to_string(rc.interval));
  if (rc.cascades < 0 || rc.cascades > 16)
    return bad("cascades: expected 0 (automatic) or 1..16, found " + std::to_string(rc.cascades));
  if (rc.extend) {
    if (rc.fix == MergeFix::bilinear)
      return bad(
          "extend: interval extension builds each probe's own interval, which the bilinear "
          "fix does not use; choose --fix none or nearest");
    if (rc.preaverage) return bad("extend: cannot be combined with pre-averaging");
    if (!(rc.extend_length >= 1.0f) || !std::isfinite(rc.extend_length))
      return bad("extend length: expected a number >= 1, found " +
                 std::to_string(rc.extend_length));
  }
  // The derived count grows as t0 shrinks; spacing s0 * 2^n and Q0 * b^n must stay sane.
  const int count =
      rc.cascades > 0 ? rc.cascades : rc::cascade_count(width, height, rc.interval, rc.branching);
  if (count > 16)
    return bad("interval t0: " + std::to_string(rc.interval) + " needs " + std::to_string(count) +
               " cascades to reach the grid diagonal, more than 16; use a larger --interval");
  const std::int64_t top = rc::top_directions(rc.directions, rc.branching, count - 1);
  if (top > rc::kMaxDirections)
    return bad("cascades: " + std::to_string(count) + " cascades give the top probes " +
               std::to_string(top) + " directions, more than " +
               std::to_string(rc::kMaxDirections) + "; use fewer cascades or directions");
  for (const rc::Cascade& c : rc::plan_cascades(width, height, rc))
    // Kernels index rows of (direction, probe row) with int.
    if (std::int64_t(c.directions) * c.probes_y > std::numeric_limits<int>::max())
      return bad("cascade " + std::to_string(c.n) + " is too large (" +
                 std::to_string(c.directions) + " directions x " + std::to_string(c.probes_y) +
                 " probe rows); use fewer directions or a larger --probe-spacing");
  return {};
}

namespace {

std::uint64_t estimate(int width, int height, const RenderOptions& o,
                       const std::vector<rc::Cascade>& plan) {
  const std::uint64_t cells = std::uint64_t(width) * height;
  // On the GPU the host holds a copy of what the device's scene holds, and the fluence.
  if (o.device == Device::gpu) return cells * (7 + 3) * sizeof(float);
  std::uint64_t bytes = cells * (sizeof(Cell) + sizeof(float));  // medium: emission and step
  if (o.method == Method::hrc) {
    bytes += hrc::working_bytes(width, height, o.hrc);
    if (o.bounces > 1) bytes += cells * 3 * sizeof(float);  // the previous bounce's fluence
    return bytes;
  }
  if (o.distance_field) bytes += distance_field_bytes(width, height);
  if (o.blocks) bytes += blocks_bytes(width, height);
  if (o.method == Method::pt) return bytes + pt::working_bytes(width, height, o.pt);
  bytes += rc::cascade_bytes(plan, o.rc);                 // cascades
  bytes += cells * 3 * sizeof(float);                     // fluence
  if (o.bounces > 1) bytes += cells * 3 * sizeof(float);  // the previous bounce's fluence
  return bytes;
}

std::string human_bytes(std::uint64_t b) {
  const char* unit[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = double(b);
  int u = 0;
  while (v >= 1024.0 && u < 4) v /= 1024.0, ++u;
  char buf[64];
  std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.2f %s", v, unit[u]);
  return buf;
}

}  // namespace

std::uint64_t estimate_memory(int width, int height, const RenderOptions& options) {
  if (!check_options(width, height, options)) return ~std::uint64_t(0);
  if (options.method != Method::rc) return estimate(width, height, options, {});
  return estimate(width, height, options, rc::plan_cascades(width, height, options.rc));
}

std::uint64_t estimate_memory(const Scene& scene, const RenderOptions& options) {
  return estimate_memory(scene.width, scene.height, options);
}

Status check_memory(int width, int height, const RenderOptions& options, bool with_scene) {
  const std::uint64_t need =
      estimate_memory(width, height, options) + (with_scene ? scene_bytes(width, height) : 0);
  if (need <= options.max_memory) return {};
  return Error{"a " + std::to_string(width) + "x" + std::to_string(height) + " grid needs " +
               human_bytes(need) + " of " +
               (with_scene ? "scene and working memory" : "working memory") + ", more than the " +
               human_bytes(options.max_memory) + " limit (raise it with --max-memory" +
               (options.method == Method::rc ? ", or use a larger --probe-spacing)"
                : options.method == Method::hrc && options.hrc.storage == Storage::f32
                    ? ", or use --storage f16)"
                    : ")")};
}

std::uint64_t scene_bytes(int width, int height) {
  return std::uint64_t(width) * height * 7 * sizeof(float);
}

// What a Renderer keeps between renders: the packed medium, HRC's buffers, and the GPU solver
// (its kernels, scene and buffers stay on the device).
struct Renderer::State {
  Medium medium;
  hrc::Workspace workspace;
  std::unique_ptr<gpu::Solver> gpu;  // on the best Vulkan device, lavapipe included
  bool gpu_tried = false;            // whether auto looked for a hardware GPU
};

namespace {

// The GPU solver a render would use: any Vulkan device for `gpu`, a hardware one for `auto`
// (null, and no error, when there is none or the options do not run on the GPU). Both take a
// hardware GPU first, so one solver serves both.
Expected<gpu::Solver*> gpu_for(const RenderOptions& o, Renderer::State& state) {
  if (o.device == Device::cpu) return static_cast<gpu::Solver*>(nullptr);
  if (o.device == Device::gpu) {
    if (!state.gpu) {
      Expected<std::shared_ptr<gpu::Context>> c = gpu::Context::create(true);
      if (!c) return c.error();
      state.gpu = std::make_unique<gpu::Solver>(*c);
    }
    return state.gpu.get();
  }
  RenderOptions as_gpu = o;
  as_gpu.device = Device::gpu;
  if (!check_options(1, 1, as_gpu)) return static_cast<gpu::Solver*>(nullptr);  // not ported
  if (!state.gpu && !state.gpu_tried) {
    state.gpu_tried = true;
    Expected<std::shared_ptr<gpu::Context>> c = gpu::Context::create(false);
    if (c) state.gpu = std::make_unique<gpu::Solver>(*c);
  }
  if (state.gpu && state.gpu->context().info().cpu) return static_cast<gpu::Solver*>(nullptr);
  return state.gpu.get();
}

}  // namespace

namespace {

Expected<RenderResult> render_unchecked(const Scene& scene, const RenderOptions& options,
                                        Renderer::State& state) {
  if (scene.width < 1 || scene.height < 1 || scene.cells() != scene.opacity.size() ||
      scene.emission.size() != 3 * scene.cells() || scene.albedo.size() != 3 * scene.cells())
    return Error{"scene: inconsistent grid (build it with build_scene)"};
  if (Status s = check_options(scene.width, scene.height, options); !s) return s.error();
  RenderResult result;
  result.options = options;
  std::vector<rc::Cascade> plan;
  if (options.method == Method::rc) {
    plan = rc::plan_cascades(scene.width, scene.height, options.rc);
    result.options.rc.cascades = int(plan.size());
  }
  if (Status s = check_memory(scene.width, scene.height, options, false); !s) return s.error();
  if (options.method == Method::hrc)
    if (Status s = hrc::check_scene(scene, options.hrc); !s) return s.error();
  result.memory_bytes = estimate(scene.width, scene.height, options, plan);

  Expected<gpu::Solver*> device = gpu_for(options, state);
  if (!device) return device.error();

  rc::fill_directions(plan);
  auto finish = [&] {  // totals of time and traced intervals
    for (const StageTime& s : result.stages) result.time_ms += s.ms;
    if (options.method == Method::rc)
      result.intervals = rc::traced_intervals(plan, options.rc) * std::uint64_t(options.bounces);
    if (options.method == Method::hrc)
      result.intervals =
          hrc::traced_intervals(scene.width, scene.height) * std::uint64_t(options.bounces);
  };
  if (*device) {  // the whole render on the GPU: the stages are its pass times
    gpu::Solver& solver = **device;
    Expected<std::vector<float>> f = solver.render(scene, options, plan, result.stages);
    if (f) {
      result.fluence = ImageRgb(scene.width, scene.height, std::move(*f));
      result.device = solver.context().info().name;
      result.gpu_memory_bytes = solver.allocated_bytes();
      result.uploaded_bytes = solver.uploaded_bytes();
      finish();
      return result;
    }
    if (options.device != Device::auto_) return f.error();
    result.stages.clear();  // auto: the CPU does it instead
    result.stages.push_back({"gpu failed, cpu used: " + f.error().message, 0.0});
  }

  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    Stopwatch watch;
    Medium& medium = state.medium;
    fill_medium(scene, medium);
    result.stages.push_back({"medium", watch.ms()});
    // HRC traces only rays a few cells long: empty-space skipping would not pay for itself.
    const bool skipping = options.method != Method::hrc;
    if (skipping && options.distance_field) {
      watch.restart();
      build_distance_field(medium);
      result.stages.push_back({"distance field", watch.ms()});
    }
    if (skipping && options.blocks) {
      watch.restart();
      build_blocks(medium);
      result.stages.push_back({"blocks", watch.ms()});
    }
    if (options.method == Method::pt) {
      std::vector<float> f = pt::solve(medium, scene.albedo, scene.environment, options, result);
      result.fluence = ImageRgb(scene.width, scene.height, std::move(f));
      return;
    }

    hrc::Workspace& workspace = state.workspace;
    auto solve = [&](std::vector<StageTime>& stages) {
      if (options.method == Method::rc)
        return rc::solve(medium, scene.environment, plan, options.rc, stages);
      std::vector<float> f;
      hrc::solve(medium, scene.environment, options.hrc, workspace, f, stages);
      return f;
    };
    std::vector<float> f = solve(result.stages);
    // More bounces: diffuse re-emission albedo * F / 2pi added to the scene's own emission.
    for (int bounce = 2; bounce <= options.bounces; ++bounce) {
      watch.restart();
      const float k = float(1.0 / (2.0 * 3.14159265358979323846));
      parallel_for(scene.height, [&](int y) {
        for (int x = 0; x < scene.width; ++x) {
          const std::size_t i = scene.index(x, y);
          const float* le = &scene.emission[3 * i];
          const float* rho = &scene.albedo[3 * i];
          Cell& c = medium.cells[i];
          c.r = le[0] + rho[0] * f[3 * i] * k;
          c.g = le[1] + rho[1] * f[3 * i + 1] * k;
          c.b = le[2] + rho[2] * f[3 * i + 2] * k;
        }
      });
      result.stages.push_back({"bounce " + std::to_string(bounce) + " emission", watch.ms()});
      std::vector<StageTime> inner;
      f = solve(inner);
      for (StageTime& s : inner)
        result.stages.push_back({"bounce " + std::to_string(bounce) + " " + s.name, s.ms});
    }
    result.fluence = ImageRgb(scene.width, scene.height, std::move(f));
  });
  finish();
  return result;
}

}  // namespace

Renderer::Renderer() : state_(std::make_unique<State>()) {}
Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;

Expected<RenderResult> Renderer::render(const Scene& scene, const RenderOptions& options) {
  // Nothing is thrown across the API: an allocation that fails despite the estimate (another
  // process took the memory) becomes an Error.
  try {
    return render_unchecked(scene, options, *state_);
  } catch (const std::bad_alloc&) {
    state_ = std::make_unique<State>();  // give back what the failed render held
    return Error{"out of memory while rendering"};
  } catch (const std::exception& e) {
    return Error{std::string("render failed: ") + e.what()};
  }
}

Expected<RenderResult> render(const Scene& scene, const RenderOptions& options) {
  Renderer renderer;
  return renderer.render(scene, options);
}

}  // namespace penumbra::flatland
