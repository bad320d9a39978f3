// libFuzzer target: the painter's stroke-file reader (parse_strokes) on arbitrary text, the
// writer round trip, and the strokes painted on a small canvas. docs/RELIABILITY.md.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string_view>

#include "flatland/paint/canvas.hpp"

namespace {

using namespace penumbra::flatland::paint;

// The guard: painting costs about points x radius^2, so only files this small are painted
// (on a canvas of at most 64 x 64 cells); the reader still sees every input.
constexpr int kMaxSide = 64;
constexpr std::size_t kMaxPoints = 256;

bool same_bits(float a, float b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// strokes_json then parse_strokes gives back every stroke bit for bit.
void check_round_trip(const StrokeFile& f) {
  penumbra::Expected<StrokeFile> back = parse_strokes(strokes_json(f), "round-trip.json");
  if (!back) std::abort();
  if (back->width != f.width || back->height != f.height) std::abort();
  if (back->strokes.size() != f.strokes.size()) std::abort();
  for (std::size_t i = 0; i < f.strokes.size(); ++i) {
    const Stroke &a = f.strokes[i], &b = back->strokes[i];
    if (a.brush.tool != b.brush.tool || !same_bits(a.brush.radius, b.brush.radius) ||
        a.points.size() != b.points.size())
      std::abort();
    for (std::size_t k = 0; k < a.points.size(); ++k)
      if (!same_bits(a.points[k][0], b.points[k][0]) || !same_bits(a.points[k][1], b.points[k][1]))
        std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  penumbra::Expected<StrokeFile> file = parse_strokes(text, "fuzz.json");
  if (!file) return 0;
  check_round_trip(*file);

  std::size_t points = 0;
  for (const Stroke& s : file->strokes) points += s.points.size();
  if (points > kMaxPoints) return 0;
  const int w = file->width > 0 ? std::min(file->width, kMaxSide) : kMaxSide;
  const int h = file->height > 0 ? std::min(file->height, kMaxSide) : kMaxSide;
  penumbra::Expected<Canvas> canvas = Canvas::blank(w, h);
  if (!canvas) std::abort();
  for (const Stroke& s : file->strokes) (void)canvas->apply(s);  // refusals are fine
  while (canvas->undo()) {
  }
  return 0;
}
