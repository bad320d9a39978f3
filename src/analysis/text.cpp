// Text through stb_easy_font: it turns a string into axis-aligned quads in font units, which are
// filled here as rectangles.
#include "analysis/text.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

// The header defines every function static; those this file does not call would warn.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#include <stb_easy_font.h>
#pragma GCC diagnostic pop

namespace penumbra::analysis {
namespace {

// stb_easy_font indexes its tables with (c - 32) and has no guard, so anything else becomes '?'.
std::string printable(std::string_view text) {
  std::string s(text);
  for (char& c : s)
    if (c < 32 || c > 126) c = '?';
  return s;
}

struct Vertex {  // stb_easy_font's vertex layout: x, y, z, RGBA
  float x, y, z;
  unsigned char rgba[4];
};
static_assert(sizeof(Vertex) == 16);

}  // namespace

void fill_rect(ImageRgb8& picture, int x, int y, int w, int h, Colour colour) {
  const int x0 = std::max(x, 0), x1 = std::min(x + w, picture.width);
  const int y0 = std::max(y, 0), y1 = std::min(y + h, picture.height);
  for (int j = y0; j < y1; ++j)
    for (int i = x0; i < x1; ++i) {
      unsigned char* p = &picture.rgb[(std::size_t(j) * picture.width + i) * 3];
      p[0] = colour[0];
      p[1] = colour[1];
      p[2] = colour[2];
    }
}

void draw_text(ImageRgb8& picture, int x, int y, std::string_view text, Colour colour, int scale) {
  std::string s = printable(text);
  // A character is at most 11 segments (quads) of 4 vertices; stb truncates a short buffer.
  std::vector<Vertex> quads(s.size() * 11 * 4 + 4);
  const int n = stb_easy_font_print(0, 0, s.data(), nullptr, quads.data(),
                                    static_cast<int>(quads.size() * sizeof(Vertex)));
  for (int q = 0; q < n; ++q) {
    const Vertex& a = quads[std::size_t(q) * 4];      // top-left
    const Vertex& b = quads[std::size_t(q) * 4 + 2];  // bottom-right
    const int x0 = static_cast<int>(std::lround(a.x * scale));
    const int y0 = static_cast<int>(std::lround(a.y * scale));
    const int x1 = static_cast<int>(std::lround(b.x * scale));
    const int y1 = static_cast<int>(std::lround(b.y * scale));
    fill_rect(picture, x + x0, y + y0, x1 - x0, y1 - y0, colour);
  }
}

int text_width(std::string_view text, int scale) {
  std::string s = printable(text);
  return stb_easy_font_width(s.data()) * scale;
}

int line_height(int scale) {
  return 12 * scale;  // stb_easy_font's line advance
}

}  // namespace penumbra::analysis
