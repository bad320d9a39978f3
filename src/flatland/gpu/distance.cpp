// Jump flooding on the GPU: seed, one dispatch per step, then distances or jumps; ping-pong seed
// buffers.
#include "flatland/gpu/distance.hpp"

#include <algorithm>
#include <cstdint>

#include "flatland/gpu/owners.hpp"
#include "flatland/gpu/shaders.hpp"

namespace penumbra::flatland::gpu {

namespace {

// Seeds and passes; returns the buffer holding the final seeds.
Expected<Buffer*> record_seeds(Cache& cache, Batch& batch, int w, int h, Buffer& step, bool timed) {
  const std::uint32_t n = std::uint32_t(std::size_t(w) * h);
  Expected<const Kernel*> seed =
      cache.kernel("jfa_seed", shaders::jfa_seed(), 2, sizeof(std::uint32_t));
  if (!seed) return seed.error();
  Expected<const Kernel*> pass =
      cache.kernel("jfa_pass", shaders::jfa_pass(), 2, 3 * sizeof(std::int32_t));
  if (!pass) return pass.error();
  Expected<Buffer*> a = cache.buffer(kJumps, "jfa seeds a", n * sizeof(std::int32_t));
  if (!a) return a.error();
  Expected<Buffer*> b = cache.buffer(kJumps, "jfa seeds b", n * sizeof(std::int32_t));
  if (!b) return b.error();
  const std::uint32_t gx = (std::uint32_t(w) + 15) / 16, gy = (std::uint32_t(h) + 15) / 16;
  Buffer* seeding[] = {&step, *a};
  if (timed) batch.mark("jfa seed");
  const Groups g = groups_1d(n, 256, cache.context().info());
  batch.dispatch(**seed, seeding, &n, g.x, g.y);
  Buffer* ping = *a;
  Buffer* pong = *b;
  for (int k : jump_flood_steps(w, h)) {
    const std::int32_t push[3] = {w, h, k};
    Buffer* io[] = {ping, pong};
    if (timed) batch.mark("jfa step " + std::to_string(k));
    batch.dispatch(**pass, io, push, gx, gy);
    std::swap(ping, pong);
  }
  return ping;
}

}  // namespace

Expected<std::vector<float>> jump_flood_distance(
    const Context& c, const Medium& m, std::vector<std::pair<std::string, double>>* passes) {
  const int w = m.width, h = m.height;
  const std::size_t n = std::size_t(w) * h;
  Cache cache(c);
  Expected<const Kernel*> finish =
      cache.kernel("jfa_distance", shaders::jfa_distance(), 2, 2 * sizeof(std::int32_t));
  if (!finish) return finish.error();
  Expected<Buffer*> step = cache.buffer(kScratch, "step", n * sizeof(float), Memory::host);
  if (!step) return step.error();
  Expected<Buffer*> out = cache.buffer(kScratch, "distance", n * sizeof(float), Memory::host);
  if (!out) return out.error();
  std::copy(m.step.begin(), m.step.end(), (*step)->as<float>());
  Expected<Batch> batch = c.batch(std::uint32_t(jump_flood_steps(w, h).size() + 2));
  if (!batch) return batch.error();
  Expected<Buffer*> seeds = record_seeds(cache, *batch, w, h, **step, true);
  if (!seeds) return seeds.error();
  const std::int32_t size[2] = {w, h};
  Buffer* last[] = {*seeds, *out};
  batch->mark("jfa distance");
  batch->dispatch(**finish, last, size, (std::uint32_t(w) + 15) / 16, (std::uint32_t(h) + 15) / 16);
  Expected<std::vector<std::pair<std::string, double>>> times = batch->run();
  if (!times) return times.error();
  if (passes) passes->insert(passes->end(), times->begin(), times->end());
  const float* d = (*out)->as<float>();
  return std::vector<float>(d, d + n);
}

Status record_distance_field(Cache& cache, Batch& batch, int w, int h, Buffer& step) {
  Expected<const Kernel*> jump =
      cache.kernel("jfa_jump", shaders::jfa_jump(), 2, 2 * sizeof(std::int32_t));
  if (!jump) return jump.error();
  batch.mark("distance field");
  Expected<Buffer*> seeds = record_seeds(cache, batch, w, h, step, false);
  if (!seeds) return seeds.error();
  const std::int32_t size[2] = {w, h};
  Buffer* bind[] = {*seeds, &step};
  batch.dispatch(**jump, bind, size, (std::uint32_t(w) + 15) / 16, (std::uint32_t(h) + 15) / 16);
  return {};
}

}  // namespace penumbra::flatland::gpu
