// How a partly covered cell takes a material: shared by the rasteriser and the painter's brush.
#pragma once

#include <cstddef>

#include "penumbra/flatland/scene.hpp"

namespace penumbra::flatland {

// Coverage of an opaque material's edge cell sharpened to c^4, so that compounding partly opaque
// edge cells keep a disk's silhouette at its true radius (see rasterize.cpp).
float opaque_edge(float c);

// The material replaces the cell's values in the covered fraction c (premultiplied "over");
// c >= 1 copies it exactly.
void blend(Scene& s, std::size_t idx, float c, const Material& m);

// The fraction to blend for a coverage c of material m: opaque_edge(c) for opaque ones.
inline float blend_fraction(float c, const Material& m) {
  return m.opacity >= 1 ? opaque_edge(c) : c;
}

}  // namespace penumbra::flatland
