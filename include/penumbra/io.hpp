// Writing results: PFM and EXR hold linear fluence, PNG a tone-mapped picture.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/scene.hpp"

namespace penumbra {

struct DisplayOptions {
  float exposure = 0;  // EV: the displayed radiance is multiplied by 2^exposure
};

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

// Writes 8-bit pictures (heatmaps, montages) as PNG files (.png names only), all or nothing as
// write_images does.
Status write_pictures(const std::vector<std::pair<std::string, ImageRgb8>>& files);

// Whether `path` can be written at all: its folder exists and it is not a folder itself. Lets a
// program refuse before it spends time computing.
Status check_output(const std::string& path);

// True when write_image knows the extension of `path`.
bool is_supported_output(const std::string& path);

// Reads a PFM or EXR file as linear RGB (used by tests and by tools that compare results).
Expected<ImageRgb> read_rgb_image(const std::string& path);

}  // namespace penumbra
