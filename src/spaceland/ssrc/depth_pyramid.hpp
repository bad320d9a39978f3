// The screen-space cascades' depth pyramid (issue 38, seed 001 section 4.2): per level, the
// nearest and farthest linear depth of the first hits under each texel, so that a march along a
// screen line skips the spans whose depth range its ray cannot meet (Hi-Z).
#pragma once

#include <cstdint>
#include <vector>

#include "spaceland/gbuffer.hpp"

namespace penumbra::spaceland::ssrc {

class DepthPyramid {
 public:
  struct Level {
    int width = 0, height = 0;
    // Per texel, the least and greatest linear depth (along the view direction) of the hits in
    // the level-0 pixels it covers; a texel over misses only has lo = +inf, hi = -inf (the sky
    // occludes nothing).
    std::vector<float> lo, hi;
  };

  // Level 0 is the G-buffer's linear depths; level l + 1 halves level l (rounding up), each texel
  // covering pixels [x 2^l, (x + 1) 2^l) x [y 2^l, (y + 1) 2^l) of the image, down to 1 x 1.
  static DepthPyramid build(const GBuffer& g);
  // Its bytes for a width x height image, known before it is built.
  static std::uint64_t bytes(int width, int height);

  int levels() const { return int(levels_.size()); }
  const Level& level(int l) const { return levels_[std::size_t(l)]; }

 private:
  std::vector<Level> levels_;
};

}  // namespace penumbra::spaceland::ssrc
