// Jump flooding on the GPU: seed, one dispatch per step, distance; ping-pong seed buffers.
#include "gpu/distance.hpp"

#include <algorithm>
#include <cstdint>

#include "gpu/shaders.hpp"

namespace penumbra::gpu {

Expected<std::vector<float>> jump_flood_distance(
    const Context& c, const Medium& m, std::vector<std::pair<std::string, double>>* passes) {
  const int w = m.width, h = m.height;
  const std::uint32_t n = std::uint32_t(std::size_t(w) * h);
  Expected<Kernel> seed = c.kernel("jfa_seed", shaders::jfa_seed(), 2, sizeof(std::uint32_t));
  if (!seed) return seed.error();
  Expected<Kernel> pass = c.kernel("jfa_pass", shaders::jfa_pass(), 2, 3 * sizeof(std::int32_t));
  if (!pass) return pass.error();
  Expected<Kernel> finish =
      c.kernel("jfa_distance", shaders::jfa_distance(), 2, 2 * sizeof(std::int32_t));
  if (!finish) return finish.error();
  Expected<Buffer> step = c.buffer(n * sizeof(float));
  if (!step) return step.error();
  Expected<Buffer> a = c.buffer(n * sizeof(std::int32_t));
  if (!a) return a.error();
  Expected<Buffer> b = c.buffer(n * sizeof(std::int32_t));
  if (!b) return b.error();
  Expected<Buffer> out = c.buffer(n * sizeof(float));
  if (!out) return out.error();
  std::copy(m.step.begin(), m.step.end(), step->as<float>());

  const std::vector<int> steps = jump_flood_steps(w, h);
  Expected<Batch> batch = c.batch(std::uint32_t(steps.size() + 2));
  if (!batch) return batch.error();
  const std::uint32_t gx = (std::uint32_t(w) + 15) / 16, gy = (std::uint32_t(h) + 15) / 16;
  Buffer* seeding[] = {&*step, &*a};
  batch->mark("jfa seed");
  const Groups g = groups_1d(n, 256, c.info());
  batch->dispatch(*seed, seeding, &n, g.x, g.y);
  Buffer* ping = &*a;
  Buffer* pong = &*b;
  for (int k : steps) {
    const std::int32_t push[3] = {w, h, k};
    Buffer* io[] = {ping, pong};
    batch->mark("jfa step " + std::to_string(k));
    batch->dispatch(*pass, io, push, gx, gy);
    std::swap(ping, pong);
  }
  const std::int32_t size[2] = {w, h};
  Buffer* last[] = {ping, &*out};
  batch->mark("jfa distance");
  batch->dispatch(*finish, last, size, gx, gy);
  Expected<std::vector<std::pair<std::string, double>>> times = batch->run();
  if (!times) return times.error();
  if (passes) passes->insert(passes->end(), times->begin(), times->end());
  const float* d = out->as<float>();
  return std::vector<float>(d, d + n);
}

}  // namespace penumbra::gpu
