// Drawing into 8-bit pictures: filled rectangles and text (stb_easy_font), for the comparison
// pictures and later plots.
#pragma once

#include <array>
#include <string_view>

#include "penumbra/image.hpp"

namespace penumbra::analysis {

using Colour = std::array<unsigned char, 3>;

// Fills [x, x + w) x [y, y + h), clipped to the picture.
void fill_rect(ImageRgb8& picture, int x, int y, int w, int h, Colour colour);

// Draws one line of ASCII text with its top-left corner at (x, y), each font unit `scale` pixels
// square; clipped to the picture. Characters outside printable ASCII are drawn as '?'.
void draw_text(ImageRgb8& picture, int x, int y, std::string_view text, Colour colour,
               int scale = 2);

// Size in pixels of a line as draw_text draws it (the height includes the space below it that
// separates lines).
int text_width(std::string_view text, int scale = 2);
int line_height(int scale = 2);

}  // namespace penumbra::analysis
