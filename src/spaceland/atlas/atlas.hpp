// A parametrisation of every surface of a 3D scene into one texture atlas, the 2D domain that
// surface radiance cascades (seed 001 section 2.5.3) and baked light live on. Each surface gets
// charts, flat pieces mapped to rectangles of texels without overlap:
// - a disk: one chart, the square around it (texels outside the disk are empty);
// - a sphere: one chart, its equal-area octahedral map (every texel of the square is on the
//   sphere, each holding the same area of it);
// - a mesh with lightmap UVs (a glTF file's TEXCOORD_1): one chart per island of them, scaled to
//   the texel size (unless they overlap: then as any mesh);
// - a mesh (boxes and quads are meshes): charts grown over neighbouring triangles whose normals
//   stay within `max_angle` of their seed's, projected on the seed's plane; a triangle that
//   would overlap one of the chart's there, or share a texel with one at another height, is
//   left for another chart.
// Texels are finer towards the lights (`refine`): a chart's texel is the atlas's halved until it
// is under 1/16 of the distance from the chart's nearest point to a light (its centre, no nearer
// than its radius: by a large light the light changes over the light's size), `refine` times at
// most (a light's own surface is not refined); a planar chart over which that changes is split into
// square tiles, each a chart of its own texel size (a quadtree over the chart's frame). A light's
// irradiance varies over distances like the distance to it, so such texels spend a budget where the
// light changes, and a ground of any size around a small light costs texels growing with the log of
// its size. The charts are packed on shelves with `gutter` empty texels around each. No UV-atlas
// library is packaged for Debian 12, hence this one. docs/METHODS.md, "The surface atlas".
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/cascade/levels.hpp"
#include "spaceland/ray.hpp"

namespace penumbra::spaceland::atlas {

struct Options {
  float texel_size = 0;             // world units a texel's side; 0: from `texels`
  std::uint64_t texels = 1u << 20;  // the surface's texels, about, where texel_size is 0
  int gutter = 2;                   // empty texels around each chart
  float max_angle = 45;             // degrees in (0, 80]: a mesh chart's normal cone
  int max_side = 16384;             // the atlas's largest side, texels
  // Texels up to 2^refine times finer towards the lights (0: one texel size). With a budget
  // (`texels`), the coarsest texel grows so that the atlas holds about as many texels.
  int refine = 0;
};

enum class ChartKind { mesh, disk, sphere };

// The lights that texels grow finer towards (Options::refine): every emitting sphere and disk,
// the box around a mesh's emitting triangles and an emitting fog box, as a centre and the radius
// of a sphere about it that holds it.
struct DensityLight {
  Vec3 centre;
  float radius = 0;
};
std::vector<DensityLight> density_lights(const Scene& scene);

struct Chart {
  ChartKind kind = ChartKind::mesh;
  std::uint32_t shape = 0;  // index into the scene's meshes, disks or spheres
  int object = -1;          // the document's object
  // A planar chart (mesh, disk) has a frame: the point of frame coordinates (s, t), in texels,
  // is origin + (s u + t v) texel_size, n = u x v its normal, and frame texel (i, j) is atlas
  // texel (shift_x + i, shift_y + j). A sphere's frame is its octahedral map, (s, t) in
  // [0, width]^2.
  Vec3 origin, u, v, n;
  int shift_x = 0, shift_y = 0;
  int x = 0, y = 0;           // its rectangle's corner in the atlas (texels, inside the gutter)
  int width = 0, height = 0;  // its rectangle, texels
  std::uint32_t first = 0, count = 0;  // a mesh chart's triangles in Atlas::chart_triangles
  // A mesh chart made from the file's lightmap UVs (an island of them, scaled): its frame's
  // coordinates are those UVs times a scale, not a projection (origin, u, v, n unused).
  bool from_lightmap = false;
  double area = 0;  // the surface's area it maps, world units squared (0: a tile's, unmeasured)
  // Its texel: the atlas's texel_size / 2^level (Options::refine).
  float texel_size = 0;
  int level = 0;
  // A tile of a split planar chart (Atlas::nodes): its corner in the split chart's frame, in the
  // atlas's texels; its triangles' Atlas::triangle_uv are in that frame.
  bool tile = false;
  int tile_x = 0, tile_y = 0;
};

// The frame a chart's direction maps are laid in (surface cascades, the radiance an atlas file
// keeps): x along a planar chart's normal, y across it and the world's z (x where the normal is
// within 26 degrees of z), z = x cross y; the world's axes for a sphere's chart and one made from
// lightmap UVs. The equal-area octahedral map's cells meet along the plane x = 0 at every
// resolution (its sign is u's), so no cell of a flat chart's maps lies across its surface: in the
// world's frame a surface facing z has the cells of the map's diamond centred in its plane, and a
// thin wall's cell traced on one side would stand for the other too.
using DirectionFrame = cascade::MapFrame;
DirectionFrame direction_frame(const Chart& c);

// A node of the quadtree that splits a planar chart into tiles, in that chart's frame (the
// atlas's texels): a leaf is a tile (chart) or nothing (no surface there); an inner node's
// children are nodes child..child+3 (x then y, low half first).
struct Node {
  int x = 0, y = 0, side = 0;
  int child = -1;
  int chart = -1;
};

// Continuous atlas coordinates, in texels (texel (i, j) spans [i, i + 1) x [j, j + 1)).
struct Uv {
  float x = 0, y = 0;
};

struct Atlas {
  int width = 0, height = 0;  // texels
  float texel_size = 0;       // world units: the coarsest texel (a chart's may be finer)
  int refine = 0;             // the levels Options::refine made (fewer where the budget asked)
  int gutter = 0;
  std::vector<Chart> charts;
  std::vector<std::uint32_t> chart_triangles;
  // Per mesh, per triangle: its chart (kSplit | k: split chart k, Atlas::splits) and its corners'
  // coordinates in the chart's frame.
  static constexpr std::uint32_t kSplit = 0x80000000u;
  std::vector<std::vector<std::uint32_t>> triangle_chart;
  std::vector<std::vector<std::array<Uv, 3>>> triangle_uv;
  // Per disk and per sphere: its chart (a disk's may be kSplit | k).
  std::vector<std::uint32_t> disk_chart, sphere_chart;
  // A planar chart split into tiles: its frame (the point of frame coordinates (s, t) is origin +
  // (s u + t v) texel_size) and its quadtree's root in `nodes`.
  struct Split {
    Vec3 origin, u, v;
    std::uint32_t root = 0;
  };
  std::vector<Split> splits;
  std::vector<Node> nodes;

  // The tile of split chart k that holds frame point p (-1: none), and p in the tile's frame.
  int tile_at(std::uint32_t k, Uv& p) const;
  // In split chart k, frame point p's tile (chart) and atlas coordinates.
  Uv in_tile(std::uint32_t k, Uv p, std::uint32_t& chart) const;
  // A mesh chart's triangle t: its corners in the chart's own frame (a tile's, for a tile).
  std::array<Uv, 3> chart_uv(const Chart& c, std::uint32_t t) const;

  // Where a surface point lies in the atlas (hit.kind, hit.shape, hit.primitive and
  // hit.position say which point), and its chart.
  Uv locate(const Scene& scene, const Hit& hit, std::uint32_t& chart) const;
};

// The area of every surface of the scene (world units squared): what a texel budget divides.
double surface_area(const Scene& scene);

// The scene's charts, packed. Errors: an atlas past `max_side` at this texel size (the message
// names the size it would need), options out of range.
Expected<Atlas> make_atlas(const Scene& scene, const Options& o = {});

// What one texel of the atlas holds: the surface point under its centre, or chart -1 (a gutter,
// a disk's corner, a gap between a chart's triangles).
struct Texel {
  int chart = -1;
  Vec3 position, normal;  // normal: the surface's geometric normal, unit
  std::uint32_t material = 0;
  int claims = 0;  // how many triangles or shapes hold its centre: at most 1 in a sound atlas
};

// Every texel's surface point: where a triangle or shape holds the texel's centre, that point (a
// centre on the shared edge of two triangles belongs to one of them, by the top-left rule, so
// no texel has two); where the chart's triangles only touch the texel (along its border, or a
// part thinner than a texel), the point of theirs nearest the centre.
std::vector<Texel> rasterise(const Scene& scene, const Atlas& atlas);

// The equal-area octahedral map (core/octahedral.hpp) of a unit direction to [0, 1]^2, and back
// (the sphere's chart).
Uv octahedral(Vec3 d);
Vec3 from_octahedral(Uv p);

// What a demanding user asks of a parametrisation: how many charts, how many mesh edges run
// between two charts (seams), the spread of the texel density over the charts of 16 texels or
// more (the chart's area in the atlas over the surface's, per texel_size^2: 1 where the map keeps
// areas, cos(max_angle) at worst on a mesh chart), and the share of the atlas that is covered.
struct Stats {
  std::size_t charts = 0;
  std::size_t lightmap_charts = 0;  // of them, made from lightmap UVs
  std::size_t seams = 0;
  double density_min = 0, density_max = 0;
  double coverage = 0;
};
Stats stats(const Scene& scene, const Atlas& atlas, const std::vector<Texel>& texels);

}  // namespace penumbra::spaceland::atlas
