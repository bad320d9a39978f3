// Reading the triangles and materials of a mesh file (OBJ + MTL, glTF 2.0 .gltf/.glb).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/spaceland/scene.hpp"

namespace penumbra::spaceland {

// A mesh file's content in the file's own coordinates (glTF node transforms already applied);
// the scene applies the object's transform.
struct MeshFile {
  TriangleMesh mesh;                  // materials index into `materials` below; object unset
  std::vector<Material> materials;    // the file's materials (a default one where it has none)
  std::vector<Texture> textures;      // referenced by materials' texture references, local indices
  std::vector<std::string> warnings;  // what the file uses and is drawn without
};

// Reads `file_path` (.obj, .gltf or .glb by extension, case-insensitive). Any failure throws
// io::JsonFailure whose message is "<scene_file>: <json_path>: <file name>: <what is wrong inside
// it>", e.g. "scene.json: objects[0].file: box.gltf: accessors[2]: index 40 out of range (24
// vertices)". Refuses, before allocating them, arrays whose size would pass `max_bytes`.
MeshFile read_mesh_file(const std::string& file_path, const std::string& scene_file,
                        const std::string& json_path, std::uint64_t max_bytes);

// A glTF file's perspective camera where its node places it, in the file's coordinates.
struct GltfCamera {
  Vec3 position, forward, up;  // forward and up: the node's -Z and +Y (not normalised)
  float fov_y = 40;            // degrees
  float aspect = 0;            // width / height, 0 where the file gives none
};

// Camera `index` of glTF file `file_path`, with read_mesh_file's messages and memory limit.
GltfCamera read_gltf_camera(const std::string& file_path, int index, const std::string& scene_file,
                            const std::string& json_path, std::uint64_t max_bytes);

// The texture's linear RGB at texture coordinates (u, v), with its wrap modes and filter.
Rgb sample_texture(const Texture& texture, float u, float v);

}  // namespace penumbra::spaceland
