// The scene as the tracers see it: per-cell emission and extinction packed together, plus the
// distance field that lets rays skip empty space.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "penumbra/scene.hpp"

namespace penumbra {

inline constexpr float kOpaque = std::numeric_limits<float>::infinity();

// One cell as a ray sees it: emitted radiance and extinction sigma per cell length
// (kOpaque for opacity 1). 16 bytes, read together.
struct Cell {
  float r, g, b;
  float sigma;
};

struct Medium {
  int width = 0, height = 0;
  std::vector<Cell> cells;  // row-major, row 0 at the top
  // Distance from each cell centre to the nearest non-empty (sigma > 0) cell centre, in cells,
  // from the jump flooding algorithm; empty when distance-field skipping is off.
  std::vector<float> distance;
  // What the tracer reads first at each step, one float per cell so the hot loop touches a
  // quarter of the memory: sigma > 0 for a cell that interacts, otherwise minus the length a ray
  // may jump from anywhere in the cell without meeting such a cell (0 when it may not jump).
  std::vector<float> step;

  const Cell& at(int x, int y) const { return cells[std::size_t(y) * width + x]; }
};

// sigma = -ln(1 - opacity) per cell length; opacity 1 is opaque.
float extinction(float opacity);

// Packs the scene's cells; `emission` (3 per cell) replaces the scene's emission when given
// (the bounce loop feeds back albedo * F / 2pi this way).
Medium make_medium(const Scene& scene, const std::vector<float>* emission = nullptr);

// Fills medium.distance with the jump flooding algorithm (seed 000, section 3.4.1) followed by
// two corrective passes (steps 2 and 1), which remove nearly all of JFA's rare errors.
void build_distance_field(Medium& medium);

// Bytes build_distance_field allocates for a grid (the field plus its two seed buffers).
std::uint64_t distance_field_bytes(int width, int height);

}  // namespace penumbra
