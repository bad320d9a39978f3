// The display encoding of fluence, shared by write_image's PNG and the comparison pictures.
#pragma once

#include <vector>

#include "penumbra/image.hpp"
#include "penumbra/io.hpp"
#include "penumbra/scene.hpp"

namespace penumbra::io {

// What a PNG of `fluence` shows, as 8-bit sRGB RGB: mean radiance F / 2pi, exposed, tone-mapped
// (ACES fit) and sRGB-encoded. With a scene (of the fluence's size, its layers complete), opaque
// cells show what they emit and reflect, as write_image does.
std::vector<unsigned char> display_rgb8(const ImageRgb& fluence, const Scene* scene,
                                        const DisplayOptions& display);

}  // namespace penumbra::io
