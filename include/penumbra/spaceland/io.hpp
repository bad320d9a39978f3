// Writing 3D results: linear PFM/EXR as computed, and a display PNG.
#pragma once

#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/io.hpp"
#include "penumbra/spaceland/render.hpp"

namespace penumbra::spaceland {

// The display picture of an image holding `aov`: radiance and emission through the exposure,
// the filmic curve and sRGB; albedo in sRGB; normals as 0.5 + 0.5 n; depth and position scaled
// to the range of the finite values (misses black); objects in distinct colours.
ImageRgb8 display_picture(const ImageRgb& image, Aov aov, const DisplayOptions& display = {});

// The exposure (EV) a light meter would choose for the PNG of a radiance or emission image:
// the median luminance of its lit pixels goes to kAutoExposureKey (penumbra/io.hpp, the same
// key as 2D's; docs/QUALITY.md, "Pictures"). 0 for the other AOVs and for a black image.
float auto_exposure(const ImageRgb& image, Aov aov);

// Writes every path (.pfm, .exr: the linear values; .png: display_picture), all or nothing.
Status write_images(const std::vector<std::string>& paths, const ImageRgb& image, Aov aov,
                    const DisplayOptions& display = {});

}  // namespace penumbra::spaceland
