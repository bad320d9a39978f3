// glTF 2.0 (.gltf, .glb) through tinygltf (Debian's shared build, stb_image and nlohmann json
// inside). tinygltf parses the JSON and loads buffers; everything it leaves unchecked is checked
// here before it is read: accessors against their buffer views and buffers, indices against the
// vertex count, values finite, the node hierarchy a tree, sizes within the memory limit. Images
// are kept encoded at load and decoded here only when a material uses them.
//
// Choices where the glTF spec leaves the reader free (docs/scene-3d.md repeats them):
// - The scene drawn is `scene`, else scenes[0]; a file without scenes draws every root node (a
//   node that is nobody's child). A scene without nodes is an empty mesh.
// - A node reached twice (a cycle, or a node with two parents) is refused, so no walk loops.
// - The whole file is one TriangleMesh with one normal per position: when some primitive has
//   NORMAL, the primitives without it get flat normals, each triangle on vertices of its own;
//   when none has, `normals` stays empty (flat shading). A normal that is not finite or has zero
//   length is refused, as a non-finite position is.
// - A primitive without material gets the glTF spec's default: baseColorFactor (1, 1, 1),
//   metallic and roughness 1, no emission. Alpha of baseColorFactor and textures is ignored.
// - Skins, morph targets, animations, cameras and lights are ignored: the rest pose is drawn.
// - Property types are checked before tinygltf reads the file (it skips wrong ones silently).
// - extensionsRequired may hold only KHR_materials_emissive_strength, KHR_mesh_quantization
//   (accessors of every component type are read) and KHR_texture_transform; Draco and meshopt
//   data are refused even when the extension is only used, since the plain data would be
//   missing. Other extensions only used are named in a warning (the file is drawn without them).
// - Textures sample TEXCOORD_0 or TEXCOORD_1 (the latter only where every primitive of the file
//   has it, as lightmap UVs are kept).
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "io/json_reader.hpp"
#include "spaceland/scene/mesh_reader.hpp"
#include "spaceland/scene/transform.hpp"

namespace penumbra::spaceland::mesh_detail {

namespace {

std::string at(const char* array, std::size_t i) {
  return std::string(array) + "[" + std::to_string(i) + "]";
}
std::string num(double v) {
  return io::format_number(v);
}

// Property names by JSON type, glTF 2.0's core (extensions' own properties are left alone).
// clang-format off
constexpr std::string_view kStrings[] = {"name", "uri", "mimeType", "version", "generator",
    "copyright", "minVersion", "alphaMode"};
constexpr std::string_view kIndices[] = {"index", "texCoord", "scene", "bufferView", "buffer",
    "byteOffset", "byteLength", "byteStride", "count", "componentType", "mesh", "skin", "camera",
    "material", "indices", "mode", "source", "sampler", "node", "input", "output", "magFilter",
    "minFilter", "wrapS", "wrapT", "skeleton", "inverseBindMatrices"};
constexpr std::string_view kNumbers[] = {"strength", "metallicFactor", "roughnessFactor",
    "alphaCutoff"};
constexpr std::string_view kObjects[] = {"asset", "pbrMetallicRoughness", "normalTexture",
    "occlusionTexture", "emissiveTexture", "baseColorTexture", "metallicRoughnessTexture",
    "attributes", "sparse", "values"};
constexpr std::string_view kArrays[] = {"primitives", "children", "nodes", "meshes", "accessors",
    "bufferViews", "buffers", "materials", "textures", "images", "samplers", "scenes", "skins",
    "cameras", "animations", "matrix", "rotation", "translation", "weights", "baseColorFactor",
    "emissiveFactor", "min", "max", "targets", "joints", "channels", "extensionsUsed",
    "extensionsRequired"};
// clang-format on

template <std::size_t N>
bool in(const std::string& key, const std::string_view (&keys)[N]) {
  return std::find(std::begin(keys), std::end(keys), key) != std::end(keys);
}

bool is_index(const nlohmann::json& v) {
  if (v.is_number_unsigned()) return true;
  if (!v.is_number_float()) return false;
  const double d = v.get<double>();
  return d >= 0 && d == std::floor(d) && d < 4e9;
}

// The JSON types of glTF 2.0's core properties, checked everywhere in the document but inside
// `extras` and extensions: tinygltf skips a property of the wrong type silently (a name of 42, an
// array for pbrMetallicRoughness, an index of -1), so such a file would load as something else.
// Draco-compressed primitives are refused here, extensionsRequired or not.
// The same walk bounds the nesting, `extras` and extensions included: tinygltf reads those into
// values of its own by recursion, so a document nested deep enough overflowed the stack (a
// 60 KB file whose `extras` nest 30,000 levels). glTF's own properties nest about 6 levels;
// past kMaxJsonDepth the file is refused, naming where.
constexpr int kMaxJsonDepth = 512;
void check_types(const nlohmann::json& doc) {
  using json = nlohmann::json;
  auto expect = [](const std::string& path, const char* what, const json& found) {
    mesh_fail(path + ": expected " + what + ", found " + io::describe(found));
  };
  struct Item {
    const json* j;
    std::string path;
    int depth;
    bool typed;  // false inside `extras` and extensions: only the nesting is checked
  };
  std::vector<Item> stack{{&doc, "", 0, true}};
  while (!stack.empty()) {
    const Item it = std::move(stack.back());
    stack.pop_back();
    const json* j = it.j;
    const std::string& path = it.path;
    if (!j->is_structured()) continue;
    if (it.depth == kMaxJsonDepth)
      mesh_fail((path.size() > 60 ? path.substr(0, 60) + "..." : path) +
                ": the JSON nests more than " + std::to_string(kMaxJsonDepth) + " levels deep");
    if (j->is_array())
      for (std::size_t i = 0; i < j->size(); ++i)
        stack.push_back({&(*j)[i], path + "[" + std::to_string(i) + "]", it.depth + 1, it.typed});
    if (!j->is_object()) continue;
    for (const auto& [key, v] : j->items()) {
      const std::string p = path.empty() ? key : path + "." + key;
      if (!it.typed || key == "extras") {
        stack.push_back({&v, p, it.depth + 1, false});
        continue;
      }
      if (key == "extensions") {
        if (!v.is_object()) expect(p, "an object", v);
        for (const auto& [ext, e] : v.items()) {
          if (!e.is_object()) expect(p + "." + ext, "an object", e);
          if (ext == "KHR_draco_mesh_compression")
            mesh_fail(path + ": Draco compression (KHR_draco_mesh_compression) is not supported");
        }
        stack.push_back({&v, p, it.depth + 1, false});
        continue;
      }
      if (in(key, kStrings) && !v.is_string()) expect(p, "a string", v);
      // A sparse accessor's indices are an object.
      const bool sparse_indices = key == "indices" && path.ends_with(".sparse");
      if (in(key, kIndices) && !is_index(v) && !sparse_indices) expect(p, "an integer >= 0", v);
      if (in(key, kNumbers) && !v.is_number()) expect(p, "a number", v);
      // A node's scale is an array, a normal texture's a number.
      if (key == "scale" && !v.is_number() && !v.is_array()) expect(p, "a number or an array", v);
      if (in(key, kObjects) && !v.is_object()) expect(p, "an object", v);
      if (in(key, kArrays) && !v.is_array()) expect(p, "an array", v);
      stack.push_back({&v, p, it.depth + 1, true});
    }
  }
}

// Before tinygltf: the version (glTF 1.0 files have objects where 2.0 has arrays; tinygltf's
// messages about them would not say what is wrong), the property types, the required extensions.
// What parsing the JSON costs, counted on its text before anything is parsed: the text twice
// (nlohmann's strings, then tinygltf's), about 1000 bytes an object (a DOM object, then a
// tinygltf::Node of 456 bytes and its members; a file of a million `{"mesh": 0}` nodes took
// 968 MiB), 64 bytes any other value (measured: a file of 200,000 translated nodes peaks at
// 295 MiB, estimated 321).
std::uint64_t json_cost(std::string_view text) {
  std::uint64_t objects = 0, values = 1;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
      continue;
    }
    if (c == '"') in_string = true;
    objects += c == '{';
    values += c == '{' || c == '[' || c == ',';
  }
  return 2 * std::uint64_t(text.size()) + 1000 * objects + 64 * values;
}

// Extensions this reader implements (extensionsRequired may name them), and those that change
// nothing it draws (metadata; material variants, whose default is what is drawn).
const std::set<std::string> kImplemented = {"KHR_materials_emissive_strength",
                                            "KHR_mesh_quantization", "KHR_texture_transform"};
const std::set<std::string> kInvisible = {"KHR_xmp_json_ld", "KHR_xmp", "KHR_materials_variants"};

void check_json(const std::string& bytes, bool binary, Budget& budget) {
  std::string_view json_text = bytes;
  if (binary) {
    std::uint32_t header[5] = {};
    if (bytes.size() < sizeof header) mesh_fail("truncated GLB header");
    std::memcpy(header, bytes.data(), sizeof header);
    if (header[1] != 2)
      mesh_fail("glTF 2.0 is needed (this file is GLB version " + std::to_string(header[1]) +
                (header[1] == 1 ? ", glTF 1.0)" : ")"));
    if (header[3] > bytes.size() - 20) mesh_fail("truncated GLB: the JSON chunk passes the end");
    json_text = json_text.substr(20, header[3]);
  }
  // The binary chunk is copied into tinygltf's buffers.
  budget.take(json_cost(json_text) + (bytes.size() - json_text.size()),
              "parsing its JSON (" + std::to_string(json_text.size()) + " bytes)");
  const nlohmann::json j = nlohmann::json::parse(json_text, nullptr, false);
  if (!j.is_object()) return;  // tinygltf's parser reports it
  const auto asset = j.find("asset");
  if (asset == j.end() || !asset->is_object() || !asset->contains("version"))
    mesh_fail("glTF 2.0 is needed (this file has no asset.version, so it is version 1.0)");
  const auto& v = (*asset)["version"];
  const std::string version = v.is_string() ? v.get<std::string>() : v.dump();
  if (version.rfind("2.", 0) != 0)
    mesh_fail("glTF 2.0 is needed (this file is version " + version + ")");
  if (j.contains("extensionsRequired"))
    for (const auto& e : j["extensionsRequired"])
      if (!e.is_string() || !kImplemented.contains(e.get<std::string>()))
        mesh_fail("extensionsRequired: " + (e.is_string() ? e.get<std::string>() : e.dump()) +
                  " is not supported");
  check_types(j);
}

// File access for tinygltf: no path expansion (the default runs wordexp), and every file it
// reads (external buffers, images) is refused past the memory limit before it is read.
struct FsState {
  Budget& budget;
  std::string failure;
};
bool file_exists(const std::string& path, void*) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}
std::string expand_path(const std::string& path, void*) {
  return path;
}
bool read_file(std::vector<unsigned char>* out, std::string* err, const std::string& path,
               void* user) {
  auto* state = static_cast<FsState*>(user);
  try {
    const std::string name = std::filesystem::path(path).filename().string();
    const std::string text = read_whole_file(path, state->budget.max(), "'" + name + "'");
    state->budget.take(text.size(), "'" + name + "'");  // tinygltf keeps a copy
    out->assign(text.begin(), text.end());
    return true;
  } catch (const MeshError& e) {
    if (state->failure.empty()) state->failure = e.what;
    if (err) *err += e.what + "\n";
  } catch (const std::exception& e) {
    if (err) *err += std::string(e.what()) + "\n";
  }
  return false;
}
bool write_file(std::string*, const std::string&, const std::vector<unsigned char>&, void*) {
  return false;
}
// Keeps images encoded; the materials decode the ones they use. An image in a buffer view is
// left where it is: tinygltf hands over the view's bytes without checking them against the
// buffer, so the materials read them through Reader::buffer_view, which does.
bool keep_image(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                const unsigned char* bytes, int size, void*) {
  if (image->bufferView < 0) image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

int component_size(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;
  }
}
const char* type_name(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR:
      return "SCALAR";
    case TINYGLTF_TYPE_VEC2:
      return "VEC2";
    case TINYGLTF_TYPE_VEC3:
      return "VEC3";
    case TINYGLTF_TYPE_VEC4:
      return "VEC4";
    default:
      return "another type";
  }
}

// One validated accessor: element i, component c as a float (normalised integers per the spec).
struct View {
  const unsigned char* data = nullptr;  // null: no bufferView, every value 0
  std::size_t stride = 0, count = 0;
  int components = 0, type = TINYGLTF_COMPONENT_TYPE_FLOAT;
  bool normalized = false;
  std::string name;  // "accessors[3]"

  double raw(std::size_t i, int c) const {
    if (!data) return 0;
    const unsigned char* p = data + i * stride + std::size_t(c) * component_size(type);
    auto load = [p](auto v) {
      std::memcpy(&v, p, sizeof v);
      return v;
    };
    switch (type) {
      case TINYGLTF_COMPONENT_TYPE_BYTE:
        return load(std::int8_t());
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return load(std::uint8_t());
      case TINYGLTF_COMPONENT_TYPE_SHORT:
        return load(std::int16_t());
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return load(std::uint16_t());
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return load(std::uint32_t());
      default:
        return load(float());
    }
  }
  float get(std::size_t i, int c) const {
    const double v = raw(i, c);
    if (!normalized || type == TINYGLTF_COMPONENT_TYPE_FLOAT) return float(v);
    const double max =
        std::ldexp(1.0, 8 * component_size(type) - (type == TINYGLTF_COMPONENT_TYPE_BYTE ||
                                                            type == TINYGLTF_COMPONENT_TYPE_SHORT
                                                        ? 1
                                                        : 0)) -
        1;
    return float(std::max(v / max, -1.0));
  }
  Vec3 vec3(std::size_t i) const { return {get(i, 0), get(i, 1), get(i, 2)}; }
};

struct Instance {
  int mesh;
  Affine world;
};

// A primitive of a mesh instance, checked, with the counts it adds.
struct PrimitivePlan {
  const Instance* instance;
  std::string name;  // "meshes[0].primitives[1]"
  int mode;
  View positions, normals, uvs, lightmap, indices;
  bool has_normals = false, has_uvs = false, has_lightmap = false, has_indices = false;
  bool samples_lightmap = false;  // a texture of its material samples TEXCOORD_1
  int material = -1;
  std::size_t triangles = 0, vertices = 0;
};

class Reader {
 public:
  Reader(const tinygltf::Model& model, Budget& budget) : m_(model), budget_(budget) {}

  MeshFile read() {
    walk_nodes();
    std::vector<PrimitivePlan> plans;
    for (const Instance& inst : instances_) {
      const auto& mesh = m_.meshes[std::size_t(inst.mesh)];
      // Counted too: a small file can instance a mesh of many primitives many times.
      budget_.take(mesh.primitives.size() * sizeof(PrimitivePlan),
                   "the primitives of the mesh instances");
      for (std::size_t p = 0; p < mesh.primitives.size(); ++p)
        plans.push_back(plan(inst, mesh.primitives[p],
                             at("meshes", std::size_t(inst.mesh)) + "." + at("primitives", p)));
    }
    bool any_normals = false, any_uvs = false, lightmap = !plans.empty();
    for (const PrimitivePlan& p : plans)
      any_normals |= p.has_normals, any_uvs |= p.has_uvs, lightmap &= p.has_lightmap;
    for (const PrimitivePlan& p : plans)
      if (p.samples_lightmap && !lightmap)
        mesh_fail(p.name +
                  ": its material samples TEXCOORD_1, which not every primitive of the file has "
                  "(the file's meshes keep a second set only when all have one)");
    std::uint64_t vertices = 0, triangles = 0;
    for (PrimitivePlan& p : plans) {
      p.vertices = any_normals && !p.has_normals ? 3 * p.triangles : p.positions.count;
      vertices += p.vertices;
      triangles += p.triangles;
    }
    budget_.take(
        mesh_bytes(vertices, any_normals, any_uvs, triangles) +
            (lightmap ? vertices * sizeof(std::array<float, 2>) : 0),
        std::to_string(triangles) + " triangles on " + std::to_string(vertices) + " vertices");
    if (vertices > UINT32_MAX) mesh_fail("more than 2^32 vertices");
    TriangleMesh& mesh = out_.mesh;
    mesh.positions.reserve(vertices);
    if (any_normals) mesh.normals.reserve(vertices);
    if (any_uvs) mesh.uvs.reserve(vertices);
    // Lightmap UVs only where every primitive has them: the atlas charts a mesh by them whole.
    if (lightmap) mesh.lightmap_uvs.reserve(vertices);
    mesh.triangles.reserve(triangles);
    mesh.materials.reserve(triangles);
    for (const PrimitivePlan& p : plans) emit(p, any_normals, any_uvs, lightmap);
    if (out_.materials.empty()) out_.materials.push_back(default_material());
    // Extensions used but not required that this reader does not implement: the file is drawn
    // without them, which the user is told (those that change nothing drawn are not named).
    for (const std::string& e : m_.extensionsUsed)
      if (!kImplemented.contains(e) && !kInvisible.contains(e))
        out_.warnings.push_back("uses " + e + ", which is not implemented: drawn without it");
    return std::move(out_);
  }

 private:
  // The node tree: children in range, one parent each, no cycle; then the scene's roots walked
  // without recursion, transforms composed down the tree.
 public:
  // Camera `index` of the file where the first node of the drawn scene (depth first, in
  // document order) that uses it places it.
  GltfCamera camera(int index) {
    const std::string where = at("cameras", std::size_t(std::max(index, 0)));
    if (index < 0 || std::size_t(index) >= m_.cameras.size())
      mesh_fail("cameras: camera " + std::to_string(index) + " does not exist (" +
                std::to_string(m_.cameras.size()) + " cameras)");
    const auto& c = m_.cameras[std::size_t(index)];
    if (c.type != "perspective")
      mesh_fail(where + ": a " + c.type + " camera (only perspective cameras are supported)");
    const double yfov = c.perspective.yfov, aspect = c.perspective.aspectRatio;
    if (!(yfov > 0 && yfov < std::numbers::pi))
      mesh_fail(where + ".perspective.yfov: " + num(float(yfov)) +
                " is not an angle in (0, pi) radians");
    if (!(aspect >= 0) || !std::isfinite(aspect))
      mesh_fail(where + ".perspective.aspectRatio: expected a finite number > 0");
    walk_nodes();
    for (const auto& [camera, world] : cameras_) {
      if (camera != index) continue;
      // glTF 2.0, 3.10.1: a camera looks down its node's -Z, with +Y up.
      GltfCamera out;
      out.position = world.point({0, 0, 0});
      out.forward = world.direction({0, 0, -1});
      out.up = world.direction({0, 1, 0});
      out.fov_y = float(yfov * 180 / std::numbers::pi);
      out.aspect = float(aspect);
      return out;
    }
    mesh_fail(where + ": no node of the drawn scene uses it");
  }

 private:
  void walk_nodes() {
    const std::size_t n = m_.nodes.size();
    std::vector<int> parent(n, -1);
    for (std::size_t i = 0; i < n; ++i)
      for (int c : m_.nodes[i].children) {
        if (c < 0 || std::size_t(c) >= n)
          mesh_fail(at("nodes", i) + ".children: node " + std::to_string(c) + " does not exist (" +
                    std::to_string(n) + " nodes)");
        if (parent[std::size_t(c)] >= 0 || std::size_t(c) == i)
          mesh_fail(at("nodes", std::size_t(c)) +
                    ": a node with two parents or in a cycle (the node hierarchy must be a tree)");
        parent[std::size_t(c)] = int(i);
      }
    // Every node reachable from a parentless one; the others sit on a cycle.
    std::vector<char> seen(n, 0);
    std::vector<std::pair<int, Affine>> stack;
    for (std::size_t i = 0; i < n; ++i)
      if (parent[i] < 0) stack.push_back({int(i), Affine{}});
    while (!stack.empty()) {
      const int i = stack.back().first;
      stack.pop_back();
      seen[std::size_t(i)] = 1;
      for (int c : m_.nodes[std::size_t(i)].children) stack.push_back({c, Affine{}});
    }
    for (std::size_t i = 0; i < n; ++i)
      if (!seen[i])
        mesh_fail(at("nodes", i) + ": the node hierarchy has a cycle (it must be a tree)");
    std::vector<int> roots;
    if (m_.scenes.empty()) {
      if (m_.defaultScene >= 0)
        mesh_fail("scene: scene " + std::to_string(m_.defaultScene) +
                  " does not exist (the file has no scenes)");
      for (std::size_t i = 0; i < n; ++i)
        if (parent[i] < 0) roots.push_back(int(i));
    } else {
      const std::size_t s = m_.defaultScene >= 0 ? std::size_t(m_.defaultScene) : 0;
      if (s >= m_.scenes.size())
        mesh_fail("scene: scene " + std::to_string(s) + " does not exist (" +
                  std::to_string(m_.scenes.size()) + " scenes)");
      for (int r : m_.scenes[s].nodes) {
        if (r < 0 || std::size_t(r) >= n)
          mesh_fail(at("scenes", s) + ".nodes: node " + std::to_string(r) + " does not exist (" +
                    std::to_string(n) + " nodes)");
        if (parent[std::size_t(r)] >= 0)
          mesh_fail(at("scenes", s) + ".nodes: " + at("nodes", std::size_t(r)) +
                    " is not a root node (it is a child of nodes[" +
                    std::to_string(parent[std::size_t(r)]) + "])");
        roots.push_back(r);
      }
    }
    // Pushed in reverse, so that meshes come out in document order.
    for (auto r = roots.rbegin(); r != roots.rend(); ++r) stack.push_back({*r, Affine{}});
    std::fill(seen.begin(), seen.end(), 0);
    while (!stack.empty()) {
      auto [i, up] = stack.back();
      stack.pop_back();
      if (seen[std::size_t(i)])
        mesh_fail(at("nodes", std::size_t(i)) + ": listed twice in the scene's nodes");
      seen[std::size_t(i)] = 1;
      const auto& node = m_.nodes[std::size_t(i)];
      const Affine world = up * local(node, at("nodes", std::size_t(i)));
      if (node.camera >= 0) cameras_.push_back({node.camera, world});
      if (node.mesh >= 0) {
        if (std::size_t(node.mesh) >= m_.meshes.size())
          mesh_fail(at("nodes", std::size_t(i)) + ".mesh: mesh " + std::to_string(node.mesh) +
                    " does not exist (" + std::to_string(m_.meshes.size()) + " meshes)");
        instances_.push_back({node.mesh, world});
      }
      for (auto c = node.children.rbegin(); c != node.children.rend(); ++c)
        stack.push_back({*c, world});
    }
  }

  static std::array<double, 4> numbers(const std::vector<double>& v, std::size_t size,
                                       std::array<double, 4> fallback, const std::string& where) {
    if (v.empty()) return fallback;
    if (v.size() != size) mesh_fail(where + ": expected " + std::to_string(size) + " numbers");
    std::array<double, 4> r{};
    for (std::size_t k = 0; k < size; ++k) {
      if (!std::isfinite(v[k])) mesh_fail(where + ": " + num(v[k]) + " is not finite");
      r[k] = v[k];
    }
    return r;
  }

  static Affine local(const tinygltf::Node& node, const std::string& where) {
    Affine a;
    if (!node.matrix.empty()) {
      if (node.matrix.size() != 16) mesh_fail(where + ".matrix: expected 16 numbers");
      for (std::size_t k = 0; k < 16; ++k)
        if (!std::isfinite(node.matrix[k]))
          mesh_fail(where + ".matrix: " + num(node.matrix[k]) + " is not finite");
      // Column-major, as glTF stores it.
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j)
          a.m[std::size_t(i * 3 + j)] = node.matrix[std::size_t(j * 4 + i)];
        a.t[std::size_t(i)] = node.matrix[std::size_t(12 + i)];
      }
      return a;
    }
    const auto t = numbers(node.translation, 3, {0, 0, 0, 0}, where + ".translation");
    const auto q = numbers(node.rotation, 4, {0, 0, 0, 1}, where + ".rotation");
    const auto s = numbers(node.scale, 3, {1, 1, 1, 0}, where + ".scale");
    const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(len > 0)) mesh_fail(where + ".rotation: a zero quaternion");
    const double x = q[0] / len, y = q[1] / len, z = q[2] / len, w = q[3] / len;
    Affine r;
    r.m = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
           2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
           2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)};
    return Affine::translate(t[0], t[1], t[2]) * r * Affine::scale(s[0], s[1], s[2]);
  }

  // Accessor `index`, used as `use` by `user`, of `type` and one of `types` (any component type
  // under KHR_mesh_quantization); its bytes checked against its buffer view and buffer.
  View view(int index, const std::string& user, const char* use, int type,
            std::initializer_list<int> types, bool normalized_ints) const {
    if (index < 0 || std::size_t(index) >= m_.accessors.size())
      mesh_fail(user + ": " + use + " accessor " + std::to_string(index) + " does not exist (" +
                std::to_string(m_.accessors.size()) + " accessors)");
    const auto& a = m_.accessors[std::size_t(index)];
    View v;
    v.name = at("accessors", std::size_t(index));
    const std::string where = v.name + " (" + use + " of " + user + ")";
    if (a.sparse.isSparse) mesh_fail(where + ": sparse accessors are not supported");
    if (a.type != type)
      mesh_fail(where + ": expected type " + type_name(type) + ", found " + type_name(a.type));
    const bool quantized = std::find(m_.extensionsUsed.begin(), m_.extensionsUsed.end(),
                                     "KHR_mesh_quantization") != m_.extensionsUsed.end();
    const int csize = component_size(a.componentType);
    const bool listed = std::find(types.begin(), types.end(), a.componentType) != types.end();
    if (csize == 0 || (!listed && !quantized) ||
        (normalized_ints && !quantized && a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT &&
         !a.normalized))
      mesh_fail(where + ": componentType " + std::to_string(a.componentType) +
                " is not allowed here");
    v.count = a.count;
    v.components = type == TINYGLTF_TYPE_SCALAR ? 1 : type - TINYGLTF_TYPE_VEC2 + 2;
    v.type = a.componentType;
    v.normalized = a.normalized;
    const std::size_t element = std::size_t(csize) * std::size_t(v.components);
    if (a.bufferView < 0) {
      // No buffer view and not sparse: every value is zero (glTF 2.0, 3.6.2.3).
      return v;
    }
    const unsigned char* bytes = buffer_view(a.bufferView, where);
    const auto& bv = m_.bufferViews[std::size_t(a.bufferView)];
    const std::string bv_name = at("bufferViews", std::size_t(a.bufferView));
    v.stride = bv.byteStride ? bv.byteStride : element;
    if (v.stride < element)
      mesh_fail(bv_name + ": byteStride " + std::to_string(bv.byteStride) + " is less than " +
                where + "'s element size " + std::to_string(element));
    // In long double: the counts come from the file and must not wrap.
    const long double need =
        v.count == 0 ? 0.0L
                     : (long double)a.byteOffset + (long double)v.stride * (v.count - 1) + element;
    if (need > (long double)bv.byteLength)
      mesh_fail(where + ": byteOffset " + std::to_string(a.byteOffset) + " + " +
                std::to_string(v.count) + " elements of stride " + std::to_string(v.stride) +
                " pass the end of " + bv_name + " (" + std::to_string(bv.byteLength) + " bytes)");
    v.data = bytes + a.byteOffset;
    return v;
  }

  // The first byte of buffer view `index`, used by `user`, once its byteOffset and byteLength are
  // checked against its buffer.
  const unsigned char* buffer_view(int index, const std::string& user) const {
    if (index < 0 || std::size_t(index) >= m_.bufferViews.size())
      mesh_fail(user + ": bufferView " + std::to_string(index) + " does not exist (" +
                std::to_string(m_.bufferViews.size()) + " buffer views)");
    const auto& bv = m_.bufferViews[std::size_t(index)];
    const std::string bv_name = at("bufferViews", std::size_t(index));
    for (const char* ext : {"EXT_meshopt_compression", "KHR_meshopt_compression"})
      if (bv.extensions.count(ext))
        mesh_fail(bv_name + ": meshopt compression (" + ext + ") is not supported");
    if (bv.buffer < 0 || std::size_t(bv.buffer) >= m_.buffers.size())
      mesh_fail(bv_name + ": buffer " + std::to_string(bv.buffer) + " does not exist (" +
                std::to_string(m_.buffers.size()) + " buffers)");
    const auto& buffer = m_.buffers[std::size_t(bv.buffer)];
    if (bv.byteOffset > buffer.data.size() || bv.byteLength > buffer.data.size() - bv.byteOffset)
      mesh_fail(bv_name + ": byteOffset " + std::to_string(bv.byteOffset) + " + byteLength " +
                std::to_string(bv.byteLength) + " passes the end of " +
                at("buffers", std::size_t(bv.buffer)) + " (" + std::to_string(buffer.data.size()) +
                " bytes)");
    return buffer.data.data() + bv.byteOffset;
  }

  PrimitivePlan plan(const Instance& inst, const tinygltf::Primitive& prim,
                     const std::string& name) {
    PrimitivePlan p;
    p.instance = &inst;
    p.name = name;
    p.mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
    static const char* const modes[] = {"POINTS", "LINES", "LINE_LOOP", "LINE_STRIP"};
    if (p.mode >= 0 && p.mode <= 3)
      mesh_fail(name + ": mode " + modes[p.mode] + " is not supported (triangles only)");
    if (p.mode > 6) mesh_fail(name + ": mode " + std::to_string(p.mode) + " is not a glTF mode");
    if (prim.extensions.count("KHR_draco_mesh_compression"))
      mesh_fail(name + ": Draco compression (KHR_draco_mesh_compression) is not supported");
    const auto attr = [&](const std::string& key) {
      const auto it = prim.attributes.find(key);
      return it == prim.attributes.end() ? -1 : it->second;
    };
    using F = std::initializer_list<int>;
    const int pos = attr("POSITION");
    if (pos < 0) mesh_fail(name + ": no POSITION attribute");
    p.positions =
        view(pos, name, "POSITION", TINYGLTF_TYPE_VEC3, F{TINYGLTF_COMPONENT_TYPE_FLOAT}, false);
    const auto same_count = [&](const View& v, const char* use) {
      if (v.count != p.positions.count)
        mesh_fail(v.name + " (" + use + " of " + name + "): " + std::to_string(v.count) +
                  " elements, POSITION has " + std::to_string(p.positions.count));
    };
    if (attr("NORMAL") >= 0) {
      p.normals = view(attr("NORMAL"), name, "NORMAL", TINYGLTF_TYPE_VEC3,
                       F{TINYGLTF_COMPONENT_TYPE_FLOAT}, false);
      same_count(p.normals, "NORMAL");
      p.has_normals = true;
    }
    p.material = prim.material;
    if (p.material >= std::int64_t(m_.materials.size()))
      mesh_fail(name + ".material: material " + std::to_string(p.material) + " does not exist (" +
                std::to_string(m_.materials.size()) + " materials)");
    if (p.material >= 0) {
      // The sets of texture coordinates the material's textures sample: TEXCOORD_0 is read as
      // the mesh's uvs, TEXCOORD_1 as its lightmap UVs.
      const auto& gm = m_.materials[std::size_t(p.material)];
      for (const TextureUse& use : texture_uses(gm, at("materials", std::size_t(p.material)))) {
        const int set = reference(*use.info, use.path).uv_set;
        const std::string name_of_set = "TEXCOORD_" + std::to_string(set);
        if (attr(name_of_set) < 0)
          mesh_fail(name + ": " + use.path + " samples " + name_of_set +
                    ", which the primitive does not have");
        if (set == 1) {
          p.samples_lightmap = true;
          continue;
        }
        if (p.has_uvs) continue;
        p.uvs = view(attr(name_of_set), name, name_of_set.c_str(), TINYGLTF_TYPE_VEC2,
                     F{TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                       TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
                     true);
        same_count(p.uvs, name_of_set.c_str());
        p.has_uvs = true;
      }
    }
    if (attr("TEXCOORD_1") >= 0) {
      p.lightmap = view(attr("TEXCOORD_1"), name, "TEXCOORD_1", TINYGLTF_TYPE_VEC2,
                        F{TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                          TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
                        true);
      same_count(p.lightmap, "TEXCOORD_1");
      p.has_lightmap = true;
    }
    std::size_t corners = p.positions.count;
    if (prim.indices >= 0) {
      p.indices =
          view(prim.indices, name, "indices", TINYGLTF_TYPE_SCALAR,
               F{TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                 TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
               false);
      if (p.indices.normalized) mesh_fail(p.indices.name + ": indices cannot be normalized");
      // Quantization allows other types for attributes, never for indices.
      if (p.indices.type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
          p.indices.type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
          p.indices.type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        mesh_fail(p.indices.name + ": indices must be unsigned integers");
      p.has_indices = true;
      corners = p.indices.count;
    }
    if (p.mode == TINYGLTF_MODE_TRIANGLES) {
      if (corners % 3 != 0)
        mesh_fail(name + ": mode TRIANGLES with " + std::to_string(corners) +
                  (p.has_indices ? " indices" : " vertices") + " (not a multiple of 3)");
      p.triangles = corners / 3;
    } else {
      p.triangles = corners >= 3 ? corners - 2 : 0;
    }
    return p;
  }

  // Vertex k of triangle t of the primitive's mode, before the index buffer.
  static std::size_t corner(int mode, std::size_t t, int k) {
    if (mode == TINYGLTF_MODE_TRIANGLES) return 3 * t + std::size_t(k);
    if (mode == TINYGLTF_MODE_TRIANGLE_FAN) return k == 0 ? 0 : t + std::size_t(k);
    // Strips: every other triangle swaps its first two corners to keep the winding.
    if (t % 2 == 1 && k < 2) return t + std::size_t(1 - k);
    return t + std::size_t(k);
  }

  void emit(const PrimitivePlan& p, bool any_normals, bool any_uvs, bool lightmap) {
    TriangleMesh& mesh = out_.mesh;
    const Affine& world = p.instance->world;
    const std::size_t n = p.positions.count, base = mesh.positions.size();
    std::vector<Vec3> pos(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 raw = p.positions.vec3(i);
      if (!std::isfinite(raw.x) || !std::isfinite(raw.y) || !std::isfinite(raw.z))
        mesh_fail(p.positions.name + ": position " + std::to_string(i) + " (" + num(raw.x) + ", " +
                  num(raw.y) + ", " + num(raw.z) + ") is not finite");
      pos[i] = world.point(raw);
      if (!std::isfinite(pos[i].x) || !std::isfinite(pos[i].y) || !std::isfinite(pos[i].z))
        mesh_fail(p.name + ": position " + std::to_string(i) +
                  " is not finite after the node transforms");
    }
    const std::uint32_t material = material_index(p.material);
    auto index = [&](std::size_t c) -> std::size_t {
      if (!p.has_indices) return c;
      const auto v = std::size_t(p.indices.raw(c, 0));
      if (v >= n)
        mesh_fail(p.indices.name + ": index " + std::to_string(v) + " out of range (" +
                  std::to_string(n) + " vertices)");
      return v;
    };
    auto coordinates = [&](const View& v, bool has, std::size_t i) {
      if (!has) return std::array<float, 2>{0, 0};
      const std::array<float, 2> t{v.get(i, 0), v.get(i, 1)};
      if (!std::isfinite(t[0]) || !std::isfinite(t[1]))
        mesh_fail(v.name + ": texture coordinate " + std::to_string(i) + " (" + num(t[0]) + ", " +
                  num(t[1]) + ") is not finite");
      return t;
    };
    auto uv = [&](std::size_t i) { return coordinates(p.uvs, p.has_uvs, i); };
    auto lightmap_uv = [&](std::size_t i) { return coordinates(p.lightmap, p.has_lightmap, i); };
    if (any_normals && !p.has_normals) {
      for (std::size_t t = 0; t < p.triangles; ++t) {
        std::size_t v[3];
        for (int k = 0; k < 3; ++k) v[k] = index(corner(p.mode, t, k));
        const Vec3 nrm = flat_normal(pos[v[0]], pos[v[1]], pos[v[2]]);
        const auto first = std::uint32_t(mesh.positions.size());
        for (int k = 0; k < 3; ++k) {
          mesh.positions.push_back(pos[v[k]]);
          mesh.normals.push_back(nrm);
          if (any_uvs) mesh.uvs.push_back(uv(v[k]));
          if (lightmap) mesh.lightmap_uvs.push_back(lightmap_uv(v[k]));
        }
        mesh.triangles.push_back({first, first + 1, first + 2});
        mesh.materials.push_back(material);
      }
      return;
    }
    for (std::size_t i = 0; i < n; ++i) {
      mesh.positions.push_back(pos[i]);
      if (any_uvs) mesh.uvs.push_back(uv(i));
      if (lightmap) mesh.lightmap_uvs.push_back(lightmap_uv(i));
      if (!any_normals) continue;
      const Vec3 raw = p.normals.vec3(i);
      const float len = length(raw);
      if (!std::isfinite(len) || !(len > 0))
        mesh_fail(p.normals.name + ": normal " + std::to_string(i) + " (" + num(raw.x) + ", " +
                  num(raw.y) + ", " + num(raw.z) + ") is not a finite non-zero vector");
      const Vec3 n = world.normal(raw / len);
      // A node scaled by 0 (or nearly) has no normal matrix.
      if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z))
        mesh_fail(p.normals.name + ": normal " + std::to_string(i) +
                  " is not finite after the node transforms (a scale of 0?)");
      mesh.normals.push_back(n);
    }
    for (std::size_t t = 0; t < p.triangles; ++t) {
      std::array<std::uint32_t, 3> tri{};
      for (int k = 0; k < 3; ++k)
        tri[std::size_t(k)] = std::uint32_t(base + index(corner(p.mode, t, k)));
      mesh.triangles.push_back(tri);
      mesh.materials.push_back(material);
    }
  }

  static Material default_material() {
    // glTF 2.0, 3.9.6: a primitive without material has baseColorFactor 1 and no emission.
    Material m;
    m.albedo = {1, 1, 1};
    m.metallic = 1;
    m.roughness = 1;
    m.name = "default (glTF)";
    return m;
  }

  std::uint32_t material_index(int gltf) {
    const auto it = materials_.find(gltf);
    if (it != materials_.end()) return it->second;
    const auto index = std::uint32_t(out_.materials.size());
    out_.materials.push_back(gltf < 0 ? default_material() : material(std::size_t(gltf)));
    materials_[gltf] = index;
    return index;
  }

  Material material(std::size_t i) {
    const auto& gm = m_.materials[i];
    const std::string where = at("materials", i);
    Material out;
    out.name = gm.name.empty() ? where : gm.name;
    const auto base = numbers(gm.pbrMetallicRoughness.baseColorFactor, 4, {1, 1, 1, 1},
                              where + ".pbrMetallicRoughness.baseColorFactor");
    const auto emissive = numbers(gm.emissiveFactor, 3, {0, 0, 0, 0}, where + ".emissiveFactor");
    double strength = 1;
    const auto ext = gm.extensions.find("KHR_materials_emissive_strength");
    if (ext != gm.extensions.end() && ext->second.Has("emissiveStrength")) {
      const auto& s = ext->second.Get("emissiveStrength");
      strength = s.IsNumber() ? s.GetNumberAsDouble() : -1;
      if (!(strength >= 0) || !std::isfinite(strength))
        mesh_fail(where +
                  ".extensions.KHR_materials_emissive_strength.emissiveStrength: "
                  "expected a finite number >= 0");
    }
    for (std::size_t c = 0; c < 3; ++c) {
      if (!(base[c] >= 0 && base[c] <= 1))
        mesh_fail(where + ".pbrMetallicRoughness.baseColorFactor: " + num(base[c]) +
                  " is outside [0, 1]");
      if (!(emissive[c] >= 0))
        mesh_fail(where + ".emissiveFactor: " + num(emissive[c]) + " is negative");
    }
    out.albedo = {float(base[0]), float(base[1]), float(base[2])};
    out.emission = {float(emissive[0] * strength), float(emissive[1] * strength),
                    float(emissive[2] * strength)};
    // glTF 2.0, 3.9.2: both factors default to 1 (a rough metal); 0 and 1 with no texture is
    // the format's Lambertian.
    const auto& pbr = gm.pbrMetallicRoughness;
    for (const auto& [name, value] : {std::pair{"metallicFactor", pbr.metallicFactor},
                                      std::pair{"roughnessFactor", pbr.roughnessFactor}})
      if (!(value >= 0 && value <= 1))
        mesh_fail(where + ".pbrMetallicRoughness." + name + ": " + num(value) +
                  " is outside [0, 1]");
    out.metallic = float(pbr.metallicFactor);
    out.roughness = float(pbr.roughnessFactor);
    for (const TextureUse& use : texture_uses(gm, where)) {
      TextureRef ref = reference(*use.info, use.path);
      ref.index =
          texture(use.info->index, use.path, use.field != &Material::metallic_roughness_texture);
      out.*use.field = ref;
    }
    return out;
  }

  // A texture a material samples: the glTF reference, its path in messages, and the material's
  // field it fills.
  struct TextureUse {
    const tinygltf::TextureInfo* info;
    std::string path;
    TextureRef Material::*field;
  };
  static std::vector<TextureUse> texture_uses(const tinygltf::Material& gm,
                                              const std::string& where) {
    const auto& pbr = gm.pbrMetallicRoughness;
    std::vector<TextureUse> uses;
    for (TextureUse u :
         {TextureUse{&pbr.baseColorTexture, where + ".pbrMetallicRoughness.baseColorTexture",
                     &Material::albedo_texture},
          TextureUse{&pbr.metallicRoughnessTexture,
                     where + ".pbrMetallicRoughness.metallicRoughnessTexture",
                     &Material::metallic_roughness_texture},
          TextureUse{&gm.emissiveTexture, where + ".emissiveTexture", &Material::emission_texture}})
      if (u.info->index >= 0) uses.push_back(std::move(u));
    return uses;
  }

  // The set of texture coordinates a reference samples and KHR_texture_transform's map on them
  // (uv' = T R S uv, the extension's order), its index not yet set.
  static TextureRef reference(const tinygltf::TextureInfo& info, const std::string& path) {
    TextureRef ref;
    int set = info.texCoord;
    const auto ext = info.extensions.find("KHR_texture_transform");
    if (ext != info.extensions.end()) {
      const tinygltf::Value& t = ext->second;
      const std::string at = path + ".extensions.KHR_texture_transform";
      auto pair = [&](const char* key, double fallback, std::array<double, 2>& out) {
        out = {fallback, fallback};
        if (!t.Has(key)) return;
        const tinygltf::Value& v = t.Get(key);
        if (!v.IsArray() || v.ArrayLen() != 2)
          mesh_fail(at + "." + key + ": expected an array of 2 numbers");
        for (int k = 0; k < 2; ++k) {
          const tinygltf::Value& e = v.Get(k);
          out[std::size_t(k)] = e.IsNumber() ? e.GetNumberAsDouble() : NAN;
          if (!std::isfinite(out[std::size_t(k)]))
            mesh_fail(at + "." + key + "[" + std::to_string(k) + "]: expected a finite number");
        }
      };
      std::array<double, 2> offset{}, scale{};
      pair("offset", 0, offset);
      pair("scale", 1, scale);
      double rotation = 0;
      if (t.Has("rotation")) {
        const tinygltf::Value& r = t.Get("rotation");
        rotation = r.IsNumber() ? r.GetNumberAsDouble() : NAN;
        if (!std::isfinite(rotation)) mesh_fail(at + ".rotation: expected a finite number");
      }
      if (t.Has("texCoord")) {
        const tinygltf::Value& c = t.Get("texCoord");
        if (!c.IsNumber() || !(c.GetNumberAsDouble() >= 0) ||
            c.GetNumberAsDouble() != std::floor(c.GetNumberAsDouble()))
          mesh_fail(at + ".texCoord: expected an integer >= 0");
        set = int(std::min(c.GetNumberAsDouble(), 1e9));
      }
      const double co = std::cos(rotation), si = std::sin(rotation);
      ref.transform = {float(co * scale[0]),  float(si * scale[1]), float(offset[0]),
                       float(-si * scale[0]), float(co * scale[1]), float(offset[1])};
    }
    if (set > 1)
      mesh_fail(path + ": samples TEXCOORD_" + std::to_string(set) +
                "; only TEXCOORD_0 and TEXCOORD_1 are supported");
    ref.uv_set = set;
    return ref;
  }

  // Texture `index` as the material's `user` samples it: sRGB-decoded (colours) or as stored
  // (metallic and roughness are linear, glTF 2.0, 3.9.3).
  int texture(int index, const std::string& user, bool srgb) {
    const auto cached = textures_.find({index, srgb});
    if (cached != textures_.end()) return cached->second;
    if (std::size_t(index) >= m_.textures.size())
      mesh_fail(user + ": texture " + std::to_string(index) + " does not exist (" +
                std::to_string(m_.textures.size()) + " textures)");
    const auto& gt = m_.textures[std::size_t(index)];
    const std::string where = at("textures", std::size_t(index));
    if (gt.source < 0 || std::size_t(gt.source) >= m_.images.size())
      mesh_fail(where + ": no source image in images (an image in an extension is not supported)");
    const auto& image = m_.images[std::size_t(gt.source)];
    const std::string iname = at("images", std::size_t(gt.source));
    const unsigned char* bytes = image.image.data();
    std::size_t length = image.image.size();
    if (image.bufferView >= 0) {
      bytes = buffer_view(image.bufferView, iname);
      length = m_.bufferViews[std::size_t(image.bufferView)].byteLength;
    }
    if (length == 0 || !image.as_is)
      mesh_fail(
          iname + ": no image data" +
          (image.uri.empty() ? "" : " ('" + image.uri.substr(0, 60) + "' could not be read)"));
    Texture t = decode_texture(bytes, length, srgb, iname, budget_);
    if (gt.sampler >= 0) {
      if (std::size_t(gt.sampler) >= m_.samplers.size())
        mesh_fail(where + ": sampler " + std::to_string(gt.sampler) + " does not exist (" +
                  std::to_string(m_.samplers.size()) + " samplers)");
      const auto& s = m_.samplers[std::size_t(gt.sampler)];
      auto wrap = [](int mode) {
        if (mode == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE) return Texture::Wrap::clamp;
        if (mode == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT) return Texture::Wrap::mirror;
        return Texture::Wrap::repeat;
      };
      t.wrap_s = wrap(s.wrapS);
      t.wrap_t = wrap(s.wrapT);
      t.nearest = s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
    }
    out_.textures.push_back(std::move(t));
    return textures_[{index, srgb}] = int(out_.textures.size() - 1);
  }

  const tinygltf::Model& m_;
  Budget& budget_;
  std::vector<Instance> instances_;
  std::vector<std::pair<int, Affine>> cameras_;  // camera index, the world of a node using it
  MeshFile out_;
  std::map<int, std::uint32_t> materials_;        // glTF material (-1: none) -> out_.materials
  std::map<std::pair<int, bool>, int> textures_;  // glTF texture, sRGB -> out_.textures
};

}  // namespace

namespace {

// Loads and checks a glTF file's model (everything read_gltf reads before its meshes).
tinygltf::Model load_model(const std::string& path, Budget& budget) {
  const std::string bytes = read_whole_file(path, budget.max(), "the file");
  budget.take(bytes.size(), "the file's bytes");
  const bool binary = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
  check_json(bytes, binary, budget);
  if (bytes.size() > UINT32_MAX) mesh_fail("files past 4 GiB are not supported (tinygltf)");

  tinygltf::TinyGLTF loader;
  FsState fs{budget, {}};
  loader.SetFsCallbacks({file_exists, expand_path, read_file, write_file, &fs});
  loader.SetImageLoader(keep_image, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const bool ok =
      binary ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                           reinterpret_cast<const unsigned char*>(bytes.data()),
                                           unsigned(bytes.size()), dir)
             : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), unsigned(bytes.size()),
                                          dir);
  if (!fs.failure.empty()) mesh_fail(fs.failure);
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    mesh_fail("invalid glTF: " + (err.empty() ? std::string("tinygltf refused it") : err));
  }
  return model;
}

}  // namespace

MeshFile read_gltf(const std::string& path, Budget& budget) {
  const tinygltf::Model model = load_model(path, budget);
  return Reader(model, budget).read();
}

GltfCamera read_gltf_camera(const std::string& path, int index, Budget& budget) {
  const tinygltf::Model model = load_model(path, budget);
  return Reader(model, budget).camera(index);
}

}  // namespace penumbra::spaceland::mesh_detail
