// The screen-space cascades on the GPU (Vulkan compute, --device gpu): render() prepares on the
// CPU what it prepares for its own cascades (the depth pyramid and its means, the probes, the
// per-pixel direct light and albedo) and hands it here (ssrc::Port); the corner weights of the
// merge and the gather are worked out on the CPU too, and the GPU runs the radiance refill of
// the pyramid per bounce, the march and merge per cascade, the gather and the shading. The
// kernels (ssrc/shaders/) repeat the CPU's arithmetic in its order, so that the images agree up
// to float rounding (docs/GPU.md gives the measured agreement).
#pragma once

#include <cstdint>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "spaceland/solve.hpp"
#include "spaceland/ssrc/ssrc.hpp"

namespace penumbra::spaceland::ssrc {

// What the port cannot do, fields named as in RenderOptions: --offscreen world's exact rays
// through the scene (Embree's, on the CPU).
Status check_gpu_options(const SsrcOptions& o);

// The port's memory besides the CPU's (Layout::bytes), known before anything is allocated, for
// the up-front check: its packed host copies of the texel records, counts and radiance, the
// light, normals and corner weights, each staged once more for the upload, the probes, the two
// cascade stores, the probes' means, the image and its readback (on lavapipe, device memory is
// host memory too).
std::uint64_t gpu_bytes(const Layout& l, const SsrcOptions& o);

// The port on the first Vulkan device (a hardware GPU, else a CPU driver such as lavapipe).
// `--rays` is a batching detail of the CPU's march and changes nothing here.
Expected<ImageRgb> render_gpu(const SolveContext& ctx, const SsrcOptions& o,
                              const Prepared& prepared, SolveReport& report);

// The same with every binding held to `binding_bytes` (0: the device's limit): a cascade's
// store larger than that is marched, and read by the gather, a slab of probes or pixels at a
// time; any other buffer larger than that is refused. Tests use it to run the slabs of a large
// image on a small one.
Expected<ImageRgb> render_gpu(const SolveContext& ctx, const SsrcOptions& o,
                              const Prepared& prepared, SolveReport& report,
                              std::uint64_t binding_bytes);

}  // namespace penumbra::spaceland::ssrc
