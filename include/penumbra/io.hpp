// Files in and out that know nothing of a scene: 8-bit pictures, linear images, output checks.
// Writing a world's results (fluence with its display PNG) is in that world's io.hpp.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"

namespace penumbra {

struct DisplayOptions {
  float exposure = 0;  // EV: the displayed radiance is multiplied by 2^exposure
  // 2D: opaque cells that emit nothing, and fog, keep a dim floor of their albedo's colour, so
  // that walls in the dark stay visible (the painter's default; `penumbra render --show-walls`).
  bool show_walls = false;
};

// What an automatic exposure maps a picture's key value (the median of its lit open cells, or
// of a 3D image's lit pixels) to, before the tone curve. 1/8 matches the exposures chosen by
// hand for the 2D example scenes within about 0.35 EV on six of eight (docs/QUALITY.md,
// "Pictures").
inline constexpr float kAutoExposureKey = 0.125f;

// Writes 8-bit pictures (heatmaps, montages) as PNG files (.png names only), all or nothing:
// every file is first written under a temporary name beside its target, and they are renamed
// into place only when all of them succeeded. SIGINT or SIGTERM meanwhile removes the temporary
// files (unless the program handles those signals itself).
Status write_pictures(const std::vector<std::pair<std::string, ImageRgb8>>& files);

// Whether `path` can be written at all: its folder exists, it is not a folder itself, and it is
// not a file the user could not write (mode 0444; for root, a file with no write bit), which
// would otherwise be silently renamed over. Lets a program refuse before it spends time
// computing; every writer checks it again.
Status check_output(const std::string& path);

// True when a result can be written to `path`: .pfm, .exr or .png (case-insensitive).
bool is_supported_output(const std::string& path);

// Reads a PFM or EXR file as linear RGB (used by tests and by tools that compare results). With
// `max_bytes`, an image whose reading would take more (7 floats a pixel) is refused from its
// header.
Expected<ImageRgb> read_rgb_image(const std::string& path, std::uint64_t max_bytes = 0);

}  // namespace penumbra
