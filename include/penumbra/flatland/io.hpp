// Writing 2D results: PFM and EXR hold linear fluence, PNG a tone-mapped picture.
#pragma once

#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/image.hpp"
#include "penumbra/io.hpp"

namespace penumbra::flatland {

// Writes `fluence` to `path`, chosen by extension (.pfm, .exr, .png, case-insensitive).
// PNG shows mean radiance F / 2pi with the scene's emitters composited, exposed, tone-mapped
// (ACES fit) and sRGB-encoded. The file appears atomically (temporary file, then rename);
// on failure nothing is left behind.
Status write_image(const std::string& path, const ImageRgb& fluence, const Scene& scene,
                   const DisplayOptions& display = {});

// Writes the same fluence to several files (each as write_image would), all or nothing: every
// file is first written under a temporary name beside its target, and they are renamed into
// place only when all of them succeeded.
Status write_images(const std::vector<std::string>& paths, const ImageRgb& fluence,
                    const Scene& scene, const DisplayOptions& display = {});

// The exposure (EV) a light meter would choose for the PNG of `fluence`: the key value, the
// median of the displayed mean radiance F / 2pi (luminance) over the lit cells that neither emit
// nor are opaque (with a scene; every lit cell without), goes to kAutoExposureKey. The median,
// not the log-average: dark corners pulled the log-average down and blew out the lit part (the
// room came out 2.3 EV brighter than its hand-set exposure). 0 when no cell is lit.
float auto_exposure(const ImageRgb& fluence, const Scene* scene);

// What a PNG of `fluence` shows, as an 8-bit sRGB picture: mean radiance F / 2pi, exposed,
// tone-mapped (ACES fit) and sRGB-encoded. With a scene (of the fluence's size, its layers
// complete), opaque cells show what they emit and reflect, as write_image does.
ImageRgb8 display_picture(const ImageRgb& fluence, const Scene* scene,
                          const DisplayOptions& display = {});

}  // namespace penumbra::flatland
