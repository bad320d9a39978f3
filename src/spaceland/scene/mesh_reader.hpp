// Private to the mesh-file readers (mesh_file.cpp, obj.cpp, gltf.cpp): their failure type, the
// memory budget and the helpers they share.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "spaceland/scene/mesh_file.hpp"

namespace penumbra::spaceland::mesh_detail {

// What is wrong inside the mesh file; read_mesh_file adds the scene file, JSON path and file name.
struct MeshError {
  std::string what;
};
[[noreturn]] inline void mesh_fail(std::string what) {
  throw MeshError{std::move(what)};
}

// Bytes of the arrays the readers allocate, counted before they are allocated.
class Budget {
 public:
  explicit Budget(std::uint64_t max_bytes) : max_(max_bytes) {}
  // Refuses when `bytes` more (what they hold: "12 triangles") would pass the limit.
  void take(std::uint64_t bytes, const std::string& what);
  std::uint64_t max() const { return max_; }

 private:
  std::uint64_t max_, used_ = 0;
};

// Bytes of a TriangleMesh's arrays for these counts.
std::uint64_t mesh_bytes(std::uint64_t vertices, bool normals, bool uvs, std::uint64_t triangles);

// The whole file, refused past `max_bytes` before it is read; `what` names it in messages.
std::string read_whole_file(const std::string& path, std::uint64_t max_bytes,
                            const std::string& what);

// An encoded image (PNG, JPEG, ... as stb_image reads them) as linear RGB texels: sRGB-decoded
// (colours) or as stored (glTF's metallic and roughness); `name` names it in messages. Refuses
// texels past the budget before decoding them.
Texture decode_texture(const unsigned char* bytes, std::size_t length, bool srgb,
                       const std::string& name, Budget& budget);

// Unit normal of triangle (a, b, c); a degenerate triangle (never hit) gets +z.
Vec3 flat_normal(Vec3 a, Vec3 b, Vec3 c);

MeshFile read_obj(const std::string& path, Budget& budget);
MeshFile read_gltf(const std::string& path, Budget& budget);
GltfCamera read_gltf_camera(const std::string& path, int index, Budget& budget);

}  // namespace penumbra::spaceland::mesh_detail
