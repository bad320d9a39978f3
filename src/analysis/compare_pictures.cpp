// The comparison pictures: the signed-error heatmap with its colour bar, and the montage of test,
// reference and error with labels and metrics.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/pictures.hpp"
#include "analysis/text.hpp"
#include "core/median.hpp"
#include "penumbra/compare.hpp"
#include "penumbra/flatland/compare.hpp"
#include "penumbra/flatland/io.hpp"
#include "penumbra/spaceland/io.hpp"

namespace penumbra::analysis {
namespace {

constexpr int kMinPanel = 256;      // narrower images are zoomed up to at least this width
constexpr int kPanelPerUnit = 170;  // font unit: panel width / 170 pixels, at least 2
constexpr int kMaxText = 8;
constexpr int kMetricLines = 2;  // below the montage
constexpr Colour kBackground{255, 255, 255};
constexpr Colour kInk{25, 25, 25};
constexpr Colour kFrame{150, 150, 150};
// The colour bar's title: how S was chosen (HeatmapOptions).
constexpr const char* kBarTitleQuantile = "S = 99th pct |err|";
constexpr const char* kBarTitleGiven = "S = given";
constexpr int kMaxPictureSide = 16384;  // pictures are shrunk to fit this a side

// The layout for a given zoom; text and spacing scale with the panel width so that a large
// picture, viewed fitted to a screen, stays legible.
PictureLayout layout_for(Zoom z, int w, int h, int panels, int metric_lines) {
  PictureLayout l;
  l.zoom = z;
  l.panels = panels;
  l.panel_w = z.pixels(w);
  l.panel_h = z.pixels(h);
  l.text = std::clamp(l.panel_w / kPanelPerUnit, 2, kMaxText);
  l.margin = 6 * l.text;
  l.gap = 8 * l.text;
  l.bar_w = 9 * l.text;
  const int line = line_height(l.text);
  for (int i = 0; i < panels; ++i) l.panel_x[i] = l.margin + i * (l.panel_w + l.gap);
  l.panel_y = l.margin + line;
  l.bar_x = l.panel_x[panels - 1] + l.panel_w + l.gap;
  l.bar_h = std::max(l.panel_h, 3 * line);  // room for three tick labels
  // The widest tick label "%+.3g" can give, so the layout does not depend on the values.
  const int column = std::max(l.bar_w + 3 * l.text + text_width("-8.88e-888", l.text),
                              text_width(kBarTitleQuantile, l.text));
  l.width = l.bar_x + column + l.margin;
  l.metrics_y = l.panel_y + l.bar_h + l.gap / 2;
  l.height = metric_lines > 0 ? l.metrics_y + metric_lines * line + l.margin
                              : l.panel_y + l.bar_h + l.margin;
  return l;
}

PictureLayout make_layout(int w, int h, int panels, int metric_lines) {
  auto fits = [&](Zoom z) {
    const PictureLayout l = layout_for(z, w, h, panels, metric_lines);
    return l.width <= kMaxPictureSide && l.height <= kMaxPictureSide;
  };
  Zoom z;
  z.zoom = w < kMinPanel ? (kMinPanel + w - 1) / w : 1;
  while (z.zoom > 1 && !fits(z)) --z.zoom;
  while (!fits(z)) ++z.shrink;
  return layout_for(z, w, h, panels, metric_lines);
}

ImageRgb8 blank(int w, int h, Colour c) {
  ImageRgb8 p{w, h, std::vector<unsigned char>(std::size_t(w) * h * 3)};
  fill_rect(p, 0, 0, w, h, c);
  return p;
}

// Cells to panel pixels: blocks when zooming, box averages when shrinking.
ImageRgb8 resample(const ImageRgb8& src, Zoom z) {
  ImageRgb8 out{z.pixels(src.width), z.pixels(src.height), {}};
  out.rgb.resize(std::size_t(out.width) * out.height * 3);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      unsigned char* o = &out.rgb[(std::size_t(y) * out.width + x) * 3];
      if (z.shrink == 1) {
        const unsigned char* s = &src.rgb[(std::size_t(y / z.zoom) * src.width + x / z.zoom) * 3];
        std::copy_n(s, 3, o);
        continue;
      }
      const int x0 = x * z.shrink, x1 = std::min(x0 + z.shrink, src.width);
      const int y0 = y * z.shrink, y1 = std::min(y0 + z.shrink, src.height);
      double sum[3] = {0, 0, 0};
      for (int j = y0; j < y1; ++j)
        for (int i = x0; i < x1; ++i)
          for (int c = 0; c < 3; ++c) sum[c] += src.rgb[(std::size_t(j) * src.width + i) * 3 + c];
      const double n = double(x1 - x0) * (y1 - y0);
      for (int c = 0; c < 3; ++c) o[c] = static_cast<unsigned char>(std::lround(sum[c] / n));
    }
  return out;
}

// Copies `src` with its top-left corner at (x, y), inside a one-pixel frame.
void place(ImageRgb8& dst, int x, int y, const ImageRgb8& src) {
  fill_rect(dst, x - 1, y - 1, src.width + 2, src.height + 2, kFrame);
  for (int j = 0; j < src.height; ++j)
    std::copy_n(&src.rgb[std::size_t(j) * src.width * 3], std::size_t(src.width) * 3,
                &dst.rgb[(std::size_t(y + j) * dst.width + x) * 3]);
}

// A label that fits `max_w` pixels: too long, it keeps its end (where a file name is) after "...".
void draw_label(ImageRgb8& p, int x, int y, const std::string& text, int max_w, int scale) {
  std::string s = text;
  while (s.size() > 3 && text_width(s, scale) > max_w) s = "..." + s.substr(4);
  draw_text(p, x, y, s, kInk, scale);
}

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// The signed error of each cell (mean of its channels' TEST - REF) in colour, one pixel a cell,
// and its scale S: HeatmapOptions::scale, or the kHeatmapScaleQuantile quantile of the counted
// cells' |error|.
ImageRgb8 error_colours(const ImageRgb& test, const ImageRgb& ref,
                        const std::vector<std::uint8_t>* mask, const HeatmapOptions& heatmap,
                        double& scale) {
  const std::size_t cells = std::size_t(ref.width()) * ref.height();
  std::vector<double> err(cells), magnitudes;
  magnitudes.reserve(cells);
  for (std::size_t i = 0; i < cells; ++i) {
    double e = 0;
    for (std::size_t k = i * 3; k < i * 3 + 3; ++k) e += double(test.data()[k]) - ref.data()[k];
    err[i] = e / 3;
    if (!mask || (*mask)[i]) magnitudes.push_back(std::abs(err[i]));
  }
  scale = heatmap.scale;
  if (!(scale > 0) && !magnitudes.empty()) {
    scale = quantile(magnitudes, kHeatmapScaleQuantile);
    // All but a few cells exact: the quantile is 0, the largest error still shows.
    if (scale == 0) scale = *std::max_element(magnitudes.begin(), magnitudes.end());
  }
  ImageRgb8 p = blank(ref.width(), ref.height(), kNotCounted);
  for (std::size_t i = 0; i < cells; ++i) {
    if (mask && !(*mask)[i]) continue;
    const Colour c = diverging(scale > 0 ? err[i] / scale : 0.0);
    std::copy(c.begin(), c.end(), &p.rgb[i * 3]);
  }
  return p;
}

Status check_heatmap(const HeatmapOptions& heatmap) {
  if (heatmap.scale >= 0 && std::isfinite(heatmap.scale)) return {};
  return Error{"heatmap scale: expected a finite number >= 0 (0: automatic)"};
}

// The last panel of `l` (the error map), its label and the colour bar with ticks at +S, 0, -S.
void draw_error_panel(ImageRgb8& p, const PictureLayout& l, const ImageRgb& test,
                      const ImageRgb& ref, const std::vector<std::uint8_t>* mask,
                      const HeatmapOptions& heatmap) {
  double scale = 0;
  const ImageRgb8 map = resample(error_colours(test, ref, mask, heatmap, scale), l.zoom);
  const int x = l.panel_x[l.panels - 1];
  place(p, x, l.panel_y, map);
  draw_label(p, x, l.margin, "test - ref, RGB mean", l.panel_w, l.text);

  ImageRgb8 bar = blank(l.bar_w, l.bar_h, kBackground);
  for (int j = 0; j < l.bar_h; ++j)
    fill_rect(bar, 0, j, l.bar_w, 1, diverging(1 - 2 * (j + 0.5) / l.bar_h));
  place(p, l.bar_x, l.panel_y, bar);
  draw_text(p, l.bar_x, l.margin, heatmap.scale > 0 ? kBarTitleGiven : kBarTitleQuantile, kInk,
            l.text);

  // Ticks inside the bar's right edge at +S, 0 and -S, labelled to its right.
  const int glyph = 7 * l.text;  // height of a digit
  const int label_x = l.bar_x + l.bar_w + 3 * l.text;
  const int ticks[3] = {l.panel_y, l.panel_y + l.bar_h / 2, l.panel_y + l.bar_h - 1};
  const std::string labels[3] = {format("%+.3g", scale), "0", format("%+.3g", -scale)};
  const int label_y[3] = {ticks[0], ticks[1] - glyph / 2, ticks[2] - glyph + 1};
  for (int i = 0; i < 3; ++i) {
    fill_rect(p, l.bar_x + l.bar_w - 3 * l.text, ticks[i], 3 * l.text, std::max(1, l.text / 2),
              kInk);
    draw_text(p, label_x, label_y[i], labels[i], kInk, l.text);
  }
}

Status check_scene(const flatland::Scene* scene, const ImageRgb& image) {
  if (!scene) return {};
  const std::size_t cells = scene->cells();
  if (scene->width != image.width() || scene->height != image.height() ||
      scene->opacity.size() != cells || scene->emission.size() != cells * 3 ||
      scene->albedo.size() != cells * 3)
    return Error{"the scene is " + std::to_string(scene->width) + "x" +
                 std::to_string(scene->height) + " but the images are " +
                 std::to_string(image.width()) + "x" + std::to_string(image.height())};
  return {};
}

}  // namespace

Colour diverging(double t) {
  // ColorBrewer RdBu, 11 classes, from -1 (blue) to +1 (red).
  static constexpr Colour kStops[11] = {{5, 48, 97},     {33, 102, 172},  {67, 147, 195},
                                        {146, 197, 222}, {209, 229, 240}, {247, 247, 247},
                                        {253, 219, 199}, {244, 165, 130}, {214, 96, 77},
                                        {178, 24, 43},   {103, 0, 31}};
  if (!(t > -1)) t = -1;  // also NaN
  if (t > 1) t = 1;
  const double u = (t + 1) * 5;  // 0 .. 10
  const int i = std::min(static_cast<int>(u), 9);
  const double f = u - i;
  Colour c;
  for (int k = 0; k < 3; ++k)
    c[k] = static_cast<unsigned char>(std::lround(kStops[i][k] * (1 - f) + kStops[i + 1][k] * f));
  return c;
}

PictureLayout heatmap_layout(int w, int h) {
  return make_layout(w, h, 1, 0);
}

PictureLayout montage_layout(int w, int h) {
  return make_layout(w, h, 3, kMetricLines);
}

}  // namespace penumbra::analysis

namespace penumbra {

using namespace analysis;

Expected<ImageRgb8> error_heatmap(const ImageRgb& test, const ImageRgb& ref,
                                  const std::vector<std::uint8_t>* mask,
                                  const HeatmapOptions& heatmap) {
  if (Status s = check_heatmap(heatmap); !s) return s.error();
  if (auto m = compare_images(test, ref, mask); !m) return m.error();
  const PictureLayout l = heatmap_layout(ref.width(), ref.height());
  ImageRgb8 p = blank(l.width, l.height, kBackground);
  draw_error_panel(p, l, test, ref, mask, heatmap);
  return p;
}

}  // namespace penumbra

namespace penumbra::flatland {

using namespace analysis;

Expected<ImageRgb8> comparison_montage(const ImageRgb& test, const ImageRgb& ref,
                                       const std::vector<std::uint8_t>* mask,
                                       const MontageOptions& options) {
  const Expected<ErrorMetrics> m = compare_images(test, ref, mask);
  if (!m) return m.error();
  if (Status s = check_scene(options.scene, ref); !s) return s.error();
  const PictureLayout l = montage_layout(ref.width(), ref.height());
  ImageRgb8 p = blank(l.width, l.height, kBackground);

  // Test and reference through the same display encoding as write_image's PNG.
  const ImageRgb* shown[2] = {&test, &ref};
  const std::string* labels[2] = {&options.test_label, &options.reference_label};
  for (int i = 0; i < 2; ++i) {
    const ImageRgb8 cells =
        options.radiance
            ? spaceland::display_picture(*shown[i], spaceland::Aov::radiance, options.display)
            : flatland::display_picture(*shown[i], options.scene, options.display);
    place(p, l.panel_x[i], l.panel_y, resample(cells, l.zoom));
    draw_label(p, l.panel_x[i], l.margin, *labels[i], l.panel_w, l.text);
  }
  if (Status s = check_heatmap(options.heatmap); !s) return s.error();
  draw_error_panel(p, l, test, ref, mask, options.heatmap);

  const std::string rel = std::isfinite(m->relative_rmse) ? format("%.3g%%", 100 * m->relative_rmse)
                                                          : std::string("inf");
  const std::string psnr = std::isnan(m->psnr)   ? std::string("n/a")
                           : std::isinf(m->psnr) ? std::string("inf")
                                                 : format("%.3g dB", m->psnr);
  const std::string lines[kMetricLines] = {
      "RMSE " + format("%.4g", m->rmse) + "   rel. RMSE " + rel + "   PSNR " + psnr + "   bias " +
          format("%+.4g", m->bias),
      "mean abs err " + format("%.4g", m->mean_abs) + "   max abs err " +
          format("%.4g", m->max_abs) + "   ref. mean " + format("%.4g", m->reference_mean) + "   " +
          std::to_string(m->cells) + (options.radiance ? " pixels" : " cells")};
  for (int i = 0; i < kMetricLines; ++i)
    draw_text(p, l.margin, l.metrics_y + i * line_height(l.text), lines[i], kInk, l.text);
  return p;
}

}  // namespace penumbra::flatland
