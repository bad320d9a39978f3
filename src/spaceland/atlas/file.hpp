// The baked atlas as a file (`penumbra bake`, `--atlas`): one EXR whose channels hold, per texel,
// the irradiance on each side of the surface (the sun's apart), the chart, and cascade 0's
// radiance per direction (what a glossy query reads); its header names the charts, the options
// the bake used and a hash of the scene, so that a view refuses an atlas baked for another scene.
// The charts themselves are not stored: make_atlas rebuilds them from the scene and the stored
// texel size, and the file's chart list must match. docs/METHODS.md, "The atlas file".
#pragma once

#include <cstdint>
#include <string>

#include "penumbra/error.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/atlas/cascades.hpp"

namespace penumbra::spaceland::atlas {

// What the bake was asked and derived, recorded in the file's header.
struct Record {
  std::uint64_t scene_hash = 0;
  float texel_size = 0;  // world units
  int gutter = 2;
  int refine = 0;  // Options::refine (absent from files before it: 0)
  float max_angle = 45;
  int directions = 0;  // Q0
  float interval = 0;  // t0, world units
  int cascades = 0;
  int bounces = 1;
  // The light is stored at 2^-light_exponent of its true scale: a scene brighter than the
  // methods compute with is baked dimmed (spaceland/brightness.hpp), and its irradiance, up to pi
  // times its radiance, might not fit a float at its true scale.
  int light_exponent = 0;
};

// A hash (64-bit FNV-1a) of what the baked light depends on: the geometry (positions, normals,
// uvs, lightmap uvs, triangles), the materials and textures, the sky and the sun. Not the camera,
// the names or the file's path: a scene moved or looked at from elsewhere keeps its atlas.
// `light` false: without the sky and the sun (what the grid's voxels are made from).
std::uint64_t scene_hash(const Scene& scene, bool light = true);

// The bake's file, built in memory (its `radiance`, where kept, in 16-bit floats unless a value
// passes their range) and written atomically: nothing at `path` unless all of it is.
Status write_atlas(const std::string& path, const Baked& baked, const Record& record);

// Reads an atlas for `scene`: refused, with the file named, if it is no Penumbra atlas, is
// damaged or truncated, was baked for another scene (hash), or its charts are not the ones this
// build makes for the scene; or if decoding it would take more than `max_bytes`.
// Without `radiance`, the directions' channels are not decoded (a view needs the irradiance).
// With `bounces` > 0, an atlas baked with other bounces is refused too. The header is checked
// before any pixel is decoded.
Expected<Baked> read_atlas(const std::string& path, const Scene& scene, std::uint64_t max_bytes,
                           Record& record, bool radiance = true, int bounces = 0);

}  // namespace penumbra::spaceland::atlas
