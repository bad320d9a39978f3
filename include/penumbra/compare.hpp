// Comparing two linear images (a result against a reference): error metrics and an error
// heatmap, for images of any world (a 2D fluence grid, a 3D camera image); each world adds its
// montage in its own compare.hpp. See docs/QUALITY.md, "Comparing two images".
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/image.hpp"
#include "penumbra/io.hpp"

namespace penumbra {

// Errors of TEST against REF. Every value is taken over the 3 channels of every counted cell,
// so n = 3 * cells values, with e = TEST - REF per value.
struct ErrorMetrics {
  std::uint64_t cells = 0;    // cells counted
  double rmse = 0;            // sqrt(sum e^2 / n)
  double relative_rmse = 0;   // rmse / reference_mean; 0 when rmse is 0, +infinity when rmse > 0
                              // and reference_mean <= 0
  double mean_abs = 0;        // sum |e| / n
  double max_abs = 0;         // max |e|
  double psnr = 0;            // 20 log10(peak / rmse) dB, peak = psnr_peak; +infinity when
                              // rmse is 0, NaN when rmse > 0 and peak <= 0
  double psnr_peak = 0;       // REF's kPsnrPeakQuantile quantile over the counted values: the
                              // bright end of what the picture shows, not a light's own cells
  double bias = 0;            // sum e / n: > 0 when TEST is brighter on average
  double reference_mean = 0;  // sum REF / n
};

// The quantile of the reference's values that PSNR takes as its peak, and the quantile of the
// cells' |signed error| that scales the heatmap by default: the largest value would be set by
// a few cells at or beside a light, and leave the rest of the picture near white.
inline constexpr double kPsnrPeakQuantile = 0.99;
inline constexpr double kHeatmapScaleQuantile = 0.99;

// How the heatmap's colours are scaled.
struct HeatmapOptions {
  double scale = 0;  // > 0: errors of +-scale take the end colours; 0: kHeatmapScaleQuantile
};

// Refuses an image holding NaN or infinity; the message starts with `name` and gives the first
// such cell.
Status check_finite(const ImageRgb& image, const std::string& name);

// Metrics of `test` against `ref` over the cells where `mask` is non-zero (all cells when null).
// Refused (Error): images of different sizes, a mask of another size, non-finite values, no cell
// counted. Sums are in double, in row order: the same inputs give the same bits.
Expected<ErrorMetrics> compare_images(const ImageRgb& test, const ImageRgb& ref,
                                      const std::vector<std::uint8_t>* mask = nullptr);

// Layout shared by the pictures: each cell is drawn as a `zoom` x `zoom` block, zoom =
// ceil(256 / width) for images narrower than 256 cells (so the labels stay legible), else 1;
// an image that would make a picture wider or taller than 16384 pixels is instead shrunk
// by an integer factor (box average of the displayed colours). Text (stb_easy_font) is drawn
// at 2 pixels per font unit, and larger with wider panels, so a big picture stays legible when
// viewed fitted to a screen.
//
// error_heatmap: the signed error of each counted cell, the mean of its 3 channels' TEST - REF,
// on a diverging scale (blue below, white at 0, red above) from -S to +S, S =
// HeatmapOptions::scale, or by default the kHeatmapScaleQuantile quantile of the counted cells'
// |signed error| (errors beyond S take the end colours); cells not counted are mid grey. A
// label above the map; to its right a vertical colour bar, titled with how S was chosen
// ("S = 99th pct |err|", "S = 99th pct, max 0.2" when cells exceed it, or "S given"), with ticks
// at +S, 0 and -S (values printed with %+.3g). Refused as compare_images refuses, and for a
// scale that is not finite and >= 0.
Expected<ImageRgb8> error_heatmap(const ImageRgb& test, const ImageRgb& ref,
                                  const std::vector<std::uint8_t>* mask = nullptr,
                                  const HeatmapOptions& heatmap = {});

}  // namespace penumbra
