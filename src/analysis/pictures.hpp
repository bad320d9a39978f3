// Internal to the comparison pictures: their colour map and layout (shared with the tests, which
// read pixels back at known places).
#pragma once

#include <array>

#include "analysis/text.hpp"

namespace penumbra::analysis {

// Colour of a signed value t in [-1, 1] (clamped): ColorBrewer's RdBu diverging map, dark blue at
// -1 through near-white at 0 to dark red at +1, interpolated linearly between its 11 classes.
Colour diverging(double t);

inline constexpr Colour kNotCounted{128, 128, 128};  // cells left out by the mask

// How cells become pixels: each cell a zoom x zoom block, or, when shrink > 1, each pixel the
// average of a shrink x shrink block of cells (the last ones partial).
struct Zoom {
  int zoom = 1, shrink = 1;
  int pixels(int cells) const { return (cells * zoom + shrink - 1) / shrink; }
};

// Where things are in a comparison picture of w x h cells. `panel_x` holds the left edge of each
// panel: one (the error map) for the heatmap; test, reference, error for the montage.
struct PictureLayout {
  int width = 0, height = 0;
  Zoom zoom;
  int text = 2;                  // font unit in pixels: 2, more for wide panels (read when shrunk)
  int margin = 0, gap = 0;       // around everything; between panels and before the bar
  int bar_w = 0;                 // the colour bar's width
  int panel_w = 0, panel_h = 0;  // pixels of one panel
  std::array<int, 3> panel_x{};
  int panels = 0;
  int panel_y = 0;    // top of every panel (the labels are above)
  int bar_x = 0;      // the colour bar, right of the last panel, from panel_y down
  int bar_h = 0;      // at least three labels tall
  int metrics_y = 0;  // the montage's lines of metrics, below the panels
};

PictureLayout heatmap_layout(int w, int h);
PictureLayout montage_layout(int w, int h);

}  // namespace penumbra::analysis
