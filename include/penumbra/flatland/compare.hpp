// Comparing 2D results: the mask of cells that hold light, and the side-by-side montage of test,
// reference and error with the fluence shown as write_image's PNG shows it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/compare.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/io.hpp"

namespace penumbra::flatland {

// A mask of the cells of `scene` that are not opaque (opacity < 1): 1 counted, 0 not. Cells
// inside walls hold no meaningful fluence, so comparisons usually leave them out.
std::vector<std::uint8_t> non_opaque_cells(const Scene& scene);

struct MontageOptions {
  std::string test_label = "test";            // above the test panel (a file name, say)
  std::string reference_label = "reference";  // above the reference panel
  DisplayOptions display;                     // exposure of the test and reference panels
  const Scene* scene = nullptr;  // optional, of the images' size: its opaque cells show what they
                                 // emit and reflect, as in write_image's PNG
  // The images are 3D radiance: shown as the 3D PNGs show them (spaceland::display_picture)
  // and counted as pixels.
  bool radiance = false;
  HeatmapOptions heatmap;  // the error panel's scale
};

// Three panels side by side: TEST and REF tone-mapped alike (as write_image's PNG), then the
// error heatmap with its colour bar; a label above each panel and the metrics (RMSE, relative
// RMSE, PSNR, bias, ...) below. Refused as compare_images refuses, and when the scene's size
// differs from the images'.
Expected<ImageRgb8> comparison_montage(const ImageRgb& test, const ImageRgb& ref,
                                       const std::vector<std::uint8_t>* mask = nullptr,
                                       const MontageOptions& options = {});

}  // namespace penumbra::flatland
