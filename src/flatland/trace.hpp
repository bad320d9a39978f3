// Tracing a ray interval through the cell grid: exact cell traversal (Amanatides-Woo DDA) that
// integrates each cell's transport analytically, with sphere-tracing jumps over empty space
// where the medium has a distance field. The jumps only skip cells that contribute nothing, so
// both paths give the same answer; the DDA is the ground truth.
#pragma once

#include "flatland/interval.hpp"
#include "flatland/medium.hpp"

namespace penumbra {

// The interval o + t*d, t in [ta, tb], with d of unit length. Outside the grid nothing emits
// or absorbs. Transport in a cell of extinction sigma over a length s: radiance Le*(1-e^-sigma s),
// transmittance e^-sigma s; an opaque cell returns Le and transmittance 0 to a ray entering it.
// With skip_start, a ray that starts strictly inside an opaque cell leaves it without
// interacting (the fluence of a wall cell is the light arriving at it); a ray starting on a
// cell boundary enters the cell it moves into.
Interval trace_interval(const Medium& m, float ox, float oy, float dx, float dy, float ta, float tb,
                        bool skip_start = false);

// The segment from point a to point b.
Interval trace_segment(const Medium& m, float ax, float ay, float bx, float by,
                       bool skip_start = false);

}  // namespace penumbra
