// HRC passes on the GPU.
#include "gpu/hrc.hpp"

#include <algorithm>
#include <cstdint>

#include "flatland/hrc/hrc.hpp"
#include "gpu/shaders.hpp"

namespace penumbra::gpu {

Expected<std::vector<float>> cross_blur(const Context& c, int width, int height,
                                        const std::vector<float>& tau_half,
                                        const std::vector<float>& fluence) {
  const std::size_t n = std::size_t(width) * height;
  if (tau_half.size() != n || fluence.size() != 3 * n)
    return Error{"cross blur: inputs do not match the " + std::to_string(width) + "x" +
                 std::to_string(height) + " grid"};
  struct Push {
    std::int32_t w, h;
    float step;
  } push{width, height, hrc::kBlurOpacityStep};
  Expected<Kernel> k = c.kernel("cross_blur", shaders::cross_blur(), 3, sizeof(Push));
  if (!k) return k.error();
  Expected<Buffer> tau = c.buffer(n * sizeof(float));
  if (!tau) return tau.error();
  Expected<Buffer> in = c.buffer(3 * n * sizeof(float));
  if (!in) return in.error();
  Expected<Buffer> out = c.buffer(3 * n * sizeof(float));
  if (!out) return out.error();
  std::copy(tau_half.begin(), tau_half.end(), tau->as<float>());
  std::copy(fluence.begin(), fluence.end(), in->as<float>());
  Expected<Batch> batch = c.batch();
  if (!batch) return batch.error();
  Buffer* buffers[] = {&*tau, &*in, &*out};
  batch->mark("cross blur");
  batch->dispatch(*k, buffers, &push, (std::uint32_t(width) + 15) / 16,
                  (std::uint32_t(height) + 15) / 16);
  if (Expected<std::vector<std::pair<std::string, double>>> r = batch->run(); !r) return r.error();
  const float* o = out->as<float>();
  return std::vector<float>(o, o + 3 * n);
}

}  // namespace penumbra::gpu
