// The viewer's upscaling: a frame rendered at the internal resolution brought to the view's,
// guided by the first hits at both (joint bilateral upsampling with the albedo divided out): each
// view pixel takes its four nearest internal pixels weighted bilinearly, by how close their depth
// is to its own and how their normals agree, so that light does not bleed across edges; the
// light they reflect is divided by their albedo and multiplied by the pixel's own, so that
// textures and edges stay sharp; a pixel that sees the sky gets the sky (through fog, the
// internal image's light).
#pragma once

#include <vector>

#include "penumbra/image.hpp"
#include "penumbra/spaceland/render.hpp"

namespace viewer {

// The channels a guide holds, in Renderer::channels' order.
inline const std::vector<penumbra::spaceland::Aov> kGuideChannels = {
    penumbra::spaceland::Aov::depth, penumbra::spaceland::Aov::normal,
    penumbra::spaceland::Aov::albedo, penumbra::spaceland::Aov::emission};

struct Guide {
  penumbra::ImageRgb depth, normal, albedo, emission;
  // From Renderer::channels(kGuideChannels).
  static Guide from(std::vector<penumbra::ImageRgb> channels);
};

// `low`'s radiance at `high`'s size (low and its guide have one size, high another). With `fog`
// (the scene has fog), a pixel that sees the sky takes the internal image's light there
// (bilinearly: the fog in front of the sky), not the sky alone.
penumbra::ImageRgb upscale(const penumbra::ImageRgb& low, const Guide& low_guide, const Guide& high,
                           bool fog);

}  // namespace viewer
