// How a partly covered cell takes a material: shared by the rasteriser and the painter's brush;
// the polygon fill's coverage and work, for tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

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

// Work done by the polygon fill, counted so that tests can check its cost law.
struct PolygonWork {
  std::uint64_t edge_visits = 0;     // edges looked at when gathering a band's or a row's edges
  std::uint64_t crossing_tests = 0;  // an edge against a row of samples or of cell centres
  std::uint64_t distance_tests = 0;  // an edge against a cell centre it may be near
  std::uint64_t cell_visits = 0;     // cells swept per row of samples or of cell centres
};

// The coverage in [0, 1] of each cell of a width x height grid (row-major) by the polygon, as
// build_scene computes it; adds the work done to *work when given.
std::vector<float> polygon_coverage(const Polygon& p, int width, int height,
                                    PolygonWork* work = nullptr);

}  // namespace penumbra::flatland
