// render(): the library's entry point for running a method on a scene.
#include "penumbra/flatland/render.hpp"

#include <tbb/task_arena.h>

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "flatland/gpu/method.hpp"
#include "flatland/gpu/solver.hpp"
#include "flatland/medium.hpp"
#include "flatland/method.hpp"
#include "gpu/vulkan.hpp"
#include "io/json_reader.hpp"

namespace penumbra::flatland {

Status check_options(int width, int height, const RenderOptions& o) {
  Expected<Plan> plan = make_plan(width, height, o);
  if (!plan) return plan.error();
  return {};
}

namespace {

std::string human_bytes(std::uint64_t b) {
  const char* unit[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = double(b);
  int u = 0;
  while (v >= 1024.0 && u < 4) v /= 1024.0, ++u;
  char buf[64];
  std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.2f %s", v, unit[u]);
  return buf;
}

// Refuses a plan whose memory need exceeds its options.max_memory: `working` (the plan's
// working_bytes), plus the rasterised scene when `with_scene` (a program that has not built the
// scene yet).
Status check_plan_memory(const Plan& plan, std::uint64_t working, bool with_scene) {
  const RenderOptions& o = plan.options;
  const std::uint64_t need = working + (with_scene ? scene_bytes(plan.width, plan.height) : 0);
  if (need <= o.max_memory) return {};
  return Error{"a " + std::to_string(plan.width) + "x" + std::to_string(plan.height) +
               " grid needs " + human_bytes(need) + " of " +
               (with_scene ? "scene and working memory" : "working memory") + ", more than the " +
               human_bytes(o.max_memory) + " limit (raise `max_memory`" +
               entry(o.method).memory_advice(o) + ")"};
}

}  // namespace

std::uint64_t estimate_memory(int width, int height, const RenderOptions& options) {
  Expected<Plan> plan = make_plan(width, height, options);
  return plan ? working_bytes(*plan) : ~std::uint64_t(0);
}

std::uint64_t estimate_memory(const Scene& scene, const RenderOptions& options) {
  return estimate_memory(scene.width, scene.height, options);
}

Status check_memory(int width, int height, const RenderOptions& options, bool with_scene) {
  Expected<Plan> plan = make_plan(width, height, options);
  if (!plan) return plan.error();  // invalid options: no memory need can be known
  return check_plan_memory(*plan, working_bytes(*plan), with_scene);
}

std::uint64_t scene_bytes(int width, int height) {
  return std::uint64_t(width) * height * 7 * sizeof(float);
}

// ---- Brightness ---------------------------------------------------------------------------
// Radiance is at most the brightest emission or environment L times the bounces (the light of
// each bounce: albedo is at most 1, so a bounce re-emits no more than the light it received), and
// fluence at most 2 pi times that. A scene whose bound passes the float range is refused; every
// method is linear in the light, so a scene too bright for the storage is rendered at 2^-k of its
// light and the result scaled back by 2^k, which only moves exponents and so is exact.

namespace {

struct Brightest {
  double value = 0;   // the largest magnitude
  std::string where;  // what holds it, for messages
};

// Refuses a brightest value whose fluence bound passes the float range.
Status within_floats(const std::string& where, double value, int bounces) {
  const double bound = kTwoPi * value * bounces;
  if (bound <= FLT_MAX) return {};
  return Error{where + ": " + io::format_number(float(value)) +  // values are floats
               " is too bright to render: the fluence can reach 2 pi x " +
               io::format_rounded(value) + " x " + std::to_string(bounces) +
               (bounces == 1 ? " bounce" : " bounces") + " = " + io::format_rounded(bound) +
               ", more than a float holds (" + io::format_rounded(FLT_MAX) +
               "); scale the scene's emission and environment down"};
}

void consider(Brightest& b, const Rgb& c, const std::string& where) {
  for (float v : {c.r, c.g, c.b})
    if (std::fabs(v) > b.value) b = {std::fabs(v), where};
}

// The largest magnitude of an RGB array (emission of a scene or layer, a result) and its index;
// `bad` is the index of the first value that is not finite (`n` when all are).
struct Peak {
  float value = 0;
  std::size_t at = 0, bad = 0;
};
Peak peak(const float* p, std::size_t n) {
  Peak k{0, 0, n};
  for (std::size_t i = 0; i < n; ++i) {
    const float v = std::fabs(p[i]);
    if (!(v <= FLT_MAX)) {  // also NaN
      k.bad = i;
      break;
    }
    if (v > k.value) k.value = v, k.at = i;
  }
  return k;
}

// "(x, y)" of the value at index i of an RGB array `width` cells wide.
std::string cell_of(std::size_t i, int width) {
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "(" + ... here.
  std::string s = "(";
  s += std::to_string(i / 3 % width);
  s += ", ";
  s += std::to_string(i / 3 / width);
  s += ')';
  return s;
}

// The brightest emission or environment of a rasterised scene; an error for a value that is not
// finite (a Scene built by hand).
Expected<Brightest> brightest(const Scene& scene) {
  const Rgb& env = scene.environment;
  if (!std::isfinite(env.r) || !std::isfinite(env.g) || !std::isfinite(env.b))
    return Error{"scene: the environment is not finite"};
  const Peak e = peak(scene.emission.data(), scene.emission.size());
  if (e.bad < scene.emission.size())
    return Error{"scene: the emission of cell " + cell_of(e.bad, scene.width) + " is not finite"};
  Brightest b;
  consider(b, env, "scene: the environment");
  if (e.value > b.value) b = {e.value, "scene: the emission of cell " + cell_of(e.at, scene.width)};
  return b;
}

// The power of two the light is divided by so that the radiance bound fits the method's storage.
int light_exponent(double radiance, const RenderOptions& o) {
  const MethodEntry& m = entry(o.method);
  const double largest = m.largest_radiance ? m.largest_radiance(o) : kLargestRadiance;
  const double bound = radiance * o.bounces;
  if (bound <= largest) return 0;
  int k = int(std::ceil(std::log2(bound / largest)));
  while (std::ldexp(bound, -k) > largest) ++k;  // log2's rounding
  return k;
}

}  // namespace

Status check_brightness(const SceneDesc& desc, const RenderOptions& options) {
  Brightest b;
  consider(b, desc.environment, "environment");
  for (std::size_t i = 0; i < desc.shapes.size(); ++i)
    consider(b, desc.shapes[i].material.emission, "shapes[" + std::to_string(i) + "].emission");
  if (const auto& layer = desc.layers.emission) {  // finite: the loader checked it
    const Peak e = peak(layer->data(), std::size_t(layer->width()) * layer->height() * 3);
    if (e.value > b.value) b = {e.value, "layers.emission: pixel " + cell_of(e.at, layer->width())};
  }
  return within_floats(desc.source + ": " + b.where, b.value, options.bounces);
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
  const MethodEntry& m = entry(o.method);
  if (!m.gpu || !gpu::supports(*m.gpu, o)) return static_cast<gpu::Solver*>(nullptr);  // not ported
  if (!state.gpu && !state.gpu_tried) {
    state.gpu_tried = true;
    Expected<std::shared_ptr<gpu::Context>> c = gpu::Context::create(false);
    if (c) state.gpu = std::make_unique<gpu::Solver>(*c);
  }
  if (state.gpu && state.gpu->context().info().cpu) return static_cast<gpu::Solver*>(nullptr);
  return state.gpu.get();
}

Expected<RenderResult> render_unchecked(const Scene& scene, const RenderOptions& options,
                                        Renderer::State& state) {
  if (scene.width < 1 || scene.height < 1 || scene.cells() != scene.opacity.size() ||
      scene.emission.size() != 3 * scene.cells() || scene.albedo.size() != 3 * scene.cells())
    return Error{"scene: inconsistent grid (build it with build_scene)"};
  // Everything derived from the grid and options, once.
  Expected<Plan> planned = make_plan(scene.width, scene.height, options);
  if (!planned) return planned.error();
  Plan& plan = *planned;
  const MethodEntry& method = entry(options.method);
  Expected<Brightest> light = brightest(scene);
  if (!light) return light.error();
  if (Status s = within_floats(light->where, light->value, options.bounces); !s) return s.error();
  const int exponent = light_exponent(light->value, options);
  RenderResult result;
  result.options = plan.options;
  // A scene rendered at a fraction of its light is a copy.
  result.memory_bytes =
      working_bytes(plan) + (exponent ? scene_bytes(scene.width, scene.height) : 0);
  if (Status s = check_plan_memory(plan, result.memory_bytes, false); !s) return s.error();
  Scene dimmed;
  if (exponent) {
    dimmed = scene;
    for (float& v : dimmed.emission) v = std::ldexp(v, -exponent);
    for (float* v : {&dimmed.environment.r, &dimmed.environment.g, &dimmed.environment.b})
      *v = std::ldexp(*v, -exponent);
  }
  const Scene& lit = exponent ? dimmed : scene;

  Expected<gpu::Solver*> device = gpu_for(options, state);
  if (!device) return device.error();

  rc::fill_directions(plan.cascades);
  // Totals of time and traced intervals; the light scaled back; nothing that is not finite
  // leaves (the bound above should make this unreachable).
  auto finish = [&]() -> Expected<RenderResult> {
    for (const StageTime& s : result.stages) result.time_ms += s.ms;
    if (method.intervals)
      result.intervals = method.intervals(plan) * std::uint64_t(options.bounces);
    float* f = result.fluence.data();
    const std::size_t n = scene.cells() * 3;
    if (exponent)
      parallel_for(scene.height, [&](int y) {
        for (std::size_t i = std::size_t(y) * scene.width * 3; i < (y + 1) * scene.width * 3ull;
             ++i)
          f[i] = std::ldexp(f[i], exponent);
      });
    if (const Peak r = peak(f, n); r.bad < n)
      return Error{std::string(method.title) + " gave a value that is not finite at cell " +
                   cell_of(r.bad, scene.width)};
    return std::move(result);
  };
  if (*device) {  // the whole render on the GPU: the stages are its pass times
    gpu::Solver& solver = **device;
    Expected<std::vector<float>> f = solver.render(lit, plan, result.stages);
    if (f) {
      result.fluence = ImageRgb(scene.width, scene.height, std::move(*f));
      result.device = solver.context().info().name;
      result.gpu_memory_bytes = solver.allocated_bytes();
      result.uploaded_bytes = solver.uploaded_bytes();
      return finish();
    }
    if (options.device != Device::auto_) return f.error();
    result.stages.clear();  // auto: the CPU does it instead
    result.stages.push_back({"gpu failed, cpu used: " + f.error().message, 0.0});
  }

  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  arena.execute([&] {
    Stopwatch watch;
    Medium& medium = state.medium;
    fill_medium(lit, medium);
    result.stages.push_back({"medium", watch.ms()});
    if (method.skips_empty_space && options.distance_field) {
      watch.restart();
      build_distance_field(medium);
      result.stages.push_back({"distance field", watch.ms()});
    }
    if (method.skips_empty_space && options.blocks) {
      watch.restart();
      build_blocks(medium);
      result.stages.push_back({"blocks", watch.ms()});
    }
    CpuSolve solve{lit, plan, medium, state.workspace, result};
    std::vector<float> f = method.solve(solve, result.stages);
    // More bounces: diffuse re-emission albedo * F / 2pi added to the scene's own emission.
    for (int bounce = 2; !method.bounces_itself && bounce <= options.bounces; ++bounce) {
      watch.restart();
      const float k = float(1.0 / kTwoPi);
      parallel_for(scene.height, [&](int y) {
        for (int x = 0; x < scene.width; ++x) {
          const std::size_t i = scene.index(x, y);
          const float* le = &lit.emission[3 * i];
          const float* rho = &scene.albedo[3 * i];
          Cell& c = medium.cells[i];
          c.r = le[0] + rho[0] * f[3 * i] * k;
          c.g = le[1] + rho[1] * f[3 * i + 1] * k;
          c.b = le[2] + rho[2] * f[3 * i + 2] * k;
        }
      });
      result.stages.push_back({"bounce " + std::to_string(bounce) + " emission", watch.ms()});
      std::vector<StageTime> inner;
      f = method.solve(solve, inner);
      for (StageTime& s : inner)
        result.stages.push_back({"bounce " + std::to_string(bounce) + " " + s.name, s.ms, s.work});
    }
    result.fluence = ImageRgb(scene.width, scene.height, std::move(f));
  });
  return finish();
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
