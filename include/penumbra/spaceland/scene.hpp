// The 3D scene: the document of docs/scene-format.md (3D, version 1) with its meshes loaded and
// every surface in world space, ready for the ray tracer. A program may also build one in code.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"
#include "penumbra/vec3.hpp"

namespace penumbra::spaceland {

// Largest image side the format allows (camera width and height, --width, --height).
inline constexpr int kMaxImageSide = 8192;

// Largest magnitude of a world coordinate: the camera, every surface (after its transform) and
// every fog box lie within [-kMaxCoordinate, kMaxCoordinate] on each axis. Embree takes ray origins
// only below 1.8e18 and squares of distances must stay within a float; this leaves room for
// both (docs/scene-format.md, "Limits").
inline constexpr float kMaxCoordinate = 1e15f;

// The pinhole camera of the format: one ray through each pixel centre (CameraRays, in
// src/spaceland/camera.hpp).
struct Camera {
  Vec3 position{0, 0, 1};
  Vec3 look_at{0, 0, 0};
  Vec3 up{0, 1, 0};
  float fov_y = 40;  // degrees, in (0, 180)
  int width = 640, height = 480;
};

// Radiance of the sky by direction: y >= 0 blends horizon to zenith, y < 0 is ground. A uniform
// sky has all three equal; the default is black.
struct Sky {
  Rgb zenith{}, horizon{}, ground{};
  bool operator==(const Sky&) const = default;
};

// A disk of uniform radiance irradiance / (pi sin^2(angular_radius)) around `direction`.
struct Sun {
  Vec3 direction{0, 1, 0};       // unit, towards the sun
  Rgb irradiance{};              // on a surface facing the sun
  float angular_radius = 0.27f;  // degrees, in (0, 45]
  bool operator==(const Sun&) const = default;
};

// Linear RGB texels, row 0 at v = 0 (glTF's convention: v runs down the image).
struct Texture {
  enum class Wrap { repeat, clamp, mirror };
  int width = 0, height = 0;
  std::vector<float> rgb;  // width * height * 3, linear (sRGB-decoded when read)
  Wrap wrap_s = Wrap::repeat, wrap_t = Wrap::repeat;
  bool nearest = false;  // magnification filter: nearest texel, else bilinear
};

// How a material samples a texture: which one, through which set of texture coordinates, and
// the affine map glTF's KHR_texture_transform (or an MTL file's -o and -s) puts on them.
struct TextureRef {
  int index = -1;  // into Scene::textures; -1: no texture
  int uv_set = 0;  // 0: TriangleMesh::uvs; 1: TriangleMesh::lightmap_uvs (glTF's TEXCOORD_1)
  // (u, v) -> (m[0] u + m[1] v + m[2], m[3] u + m[4] v + m[5])
  std::array<float, 6> transform{1, 0, 0, 0, 1, 0};
};

// A reflector and emitter: glTF 2.0's metallic-roughness BRDF (docs/scene-format.md, "Glossy
// materials"), which is version 1's Lambertian where metallic is 0 and roughness 1.
struct Material {
  Rgb albedo{0.8f, 0.8f, 0.8f};           // base colour in [0, 1]; times albedo_texture's texel
  Rgb emission{};                         // radiance, >= 0; times emission_texture's texel
  float metallic = 0;                     // in [0, 1]; times metallic_roughness_texture's blue
  float roughness = 1;                    // in [0, 1]; times metallic_roughness_texture's green
  TextureRef albedo_texture;              // sRGB-decoded texels
  TextureRef emission_texture;            // sRGB-decoded texels
  TextureRef metallic_roughness_texture;  // linear texels (glTF's metallicRoughnessTexture)
  std::string name;                       // for messages

  // Version 1's Lambertian everywhere on the surface: no specular lobe.
  bool lambertian() const {
    return metallic == 0 && roughness == 1 && metallic_roughness_texture.index < 0;
  }
};

// Triangles of one object in world space: a mesh file, a box, a quad, or a sphere or disk that a
// non-uniform scale turned into an ellipsoid or an ellipse (tessellated).
struct TriangleMesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;              // one per position (unit), or empty: flat triangles
  std::vector<std::array<float, 2>> uvs;  // one per position, or empty
  // A glTF file's second UV set (TEXCOORD_1, the lightmap UVs artists make), one per position,
  // or empty: the surface atlas charts the mesh by its islands (src/spaceland/atlas).
  std::vector<std::array<float, 2>> lightmap_uvs;
  std::vector<std::array<std::uint32_t, 3>> triangles;  // indices into positions
  std::vector<std::uint32_t> materials;  // one per triangle: index into Scene::materials
  int object = -1;                       // index of the document's object
};

// Exact analytic shapes (objects with a uniform scale).
struct Sphere {
  Vec3 center;
  float radius = 1;
  std::uint32_t material = 0;
  int object = -1;
};
struct Disk {
  Vec3 center;
  Vec3 normal{0, 1, 0};  // unit
  float radius = 1;
  std::uint32_t material = 0;
  int object = -1;
};

// A box of homogeneous fog.
struct Medium {
  Vec3 center;
  Vec3 half_size{0.5f, 0.5f, 0.5f};
  std::array<Vec3, 3> axes{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};  // unit, orthogonal
  Rgb extinction{};                                                       // per world unit, >= 0
  Rgb albedo{};    // single-scattering albedo in [0, 1]; isotropic phase function
  Rgb emission{};  // radiance per unit length, >= 0
};

struct Scene {
  Camera camera;
  Sky sky;
  bool has_sun = false;
  Sun sun;
  std::vector<Material> materials;
  std::vector<Texture> textures;
  std::vector<TriangleMesh> meshes;
  std::vector<Sphere> spheres;
  std::vector<Disk> disks;
  std::vector<Medium> media;
  // One line per object of the document ("objects[2] (sphere)"), indexed by `object` above.
  std::vector<std::string> objects;
  std::string source = "<code>";  // file name used in messages
  // What the document's files use and the scene is drawn without ("objects[1].file: car.glb:
  // uses KHR_materials_clearcoat, ..."); render() passes them on in RenderResult::warnings.
  std::vector<std::string> warnings;
};

struct LoadOptions {
  // Mesh data (vertices, triangles, textures) past this many bytes is refused, before the
  // arrays are allocated where the file's header tells their size.
  std::uint64_t max_memory = std::uint64_t(8) << 30;
};

// Parses a version-1 3D document. `path` names the file in messages and anchors relative mesh
// paths. Every rule of the format is checked; a message names the file, the JSON path and, for a
// mesh file, what is wrong inside it.
Expected<Scene> parse_scene(std::string_view json_text, const std::string& path,
                            const LoadOptions& options = {});

// Reads and parses a 3D scene file.
Expected<Scene> load_scene(const std::string& path, const LoadOptions& options = {});

// 2 or 3: the `dimensions` of a scene document (2 when absent), for programs that read both
// worlds. Errors: unreadable file, invalid JSON, `dimensions` not 2 or 3, or absent from a
// document with 3D keys (`camera`, `objects`).
Expected<int> scene_dimensions(const std::string& path);

// Checks a scene built in code as parse_scene checks a document: finite values in range, indices
// in range, unit vectors. render() calls it.
Status check_scene(const Scene& scene);

// Axis-aligned bounds of every surface (media and the camera excluded); empty scene: the origin.
struct Bounds {
  Vec3 lo, hi;
};
Bounds scene_bounds(const Scene& scene);

// Bytes the scene's arrays hold (vertices, triangles, textures).
std::uint64_t scene_bytes(const Scene& scene);

}  // namespace penumbra::spaceland
