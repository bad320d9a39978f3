// The scene as the tracers see it: per-cell emission and extinction packed together, plus the
// distance field that lets rays skip empty space.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "penumbra/flatland/scene.hpp"

namespace penumbra::flatland {

inline constexpr float kOpaque = std::numeric_limits<float>::infinity();

// Radiance a cell emits; read only when the cell interacts (step > 0).
struct Cell {
  float r, g, b;
};

struct Medium {
  int width = 0, height = 0;
  std::vector<Cell> cells;  // row-major, row 0 at the top
  // What the tracer reads first at each step, one float per cell so the hot loop touches little
  // memory: the extinction sigma per cell length (kOpaque for opacity 1) of a cell that
  // interacts, otherwise minus the length a ray may jump from anywhere in the cell without
  // meeting one (0: it may not jump, as before build_distance_field).
  std::vector<float> step;
  // The block level of the two-level DDA: 1 where an 8x8 block of cells has no interacting cell
  // (empty until build_blocks).
  int blocks_x = 0, blocks_y = 0;
  std::vector<std::uint8_t> block_empty;
};

inline constexpr int kBlockShift = 3;  // blocks of 8x8 cells
// In an empty block the tracer takes a distance-field jump longer than this (in cells) instead of
// walking blocks: a jump costs a re-location, a block step about a cell step's work for up to
// 8 sqrt 2 cells, and past about two block diagonals the jump measured faster
// (docs/PERFORMANCE.md).
inline constexpr float kJumpOverBlocks = 24.0f;

// sigma = -ln(1 - opacity) per cell length; opacity 1 is opaque.
float extinction(float opacity);

// Packs the scene's cells for the tracer.
Medium make_medium(const Scene& scene);
// The same into an existing medium, reusing its memory (no distance field, no blocks).
void fill_medium(const Scene& scene, Medium& medium);

// Distance from each cell centre to the nearest interacting (step > 0) cell centre, in cells
// (infinity when there is none): the jump flooding algorithm (seed 000, section 3.4.1) followed
// by two corrective passes (steps 2 and 1), which remove nearly all of JFA's rare errors.
std::vector<float> jump_flood_distance(const Medium& medium);
// The passes' steps: powers of two from the largest below the grid's side down to 1, then the
// corrective 2 and 1 (shared with the GPU backend).
std::vector<int> jump_flood_steps(int width, int height);

// Writes the jump length of every empty cell into medium.step, from jump_flood_distance.
void build_distance_field(Medium& medium);

// Marks the 8x8 blocks that hold no interacting cell. Call after the step values are final
// (before or after build_distance_field: jumps are not interactions).
void build_blocks(Medium& medium);
std::uint64_t blocks_bytes(int width, int height);

// Bytes build_distance_field allocates at its peak (the distances and two seed buffers).
std::uint64_t distance_field_bytes(int width, int height);

}  // namespace penumbra::flatland
