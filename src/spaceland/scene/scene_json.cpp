// Reading 3D scene documents (docs/scene-format.md, 3D scenes, version 1).
//
// The document is walked once: structure, types and ranges are checked as each value is read
// (the 2D loader's JsonReader, so messages read the same), each object is turned into world-space
// triangles or analytic shapes as it comes, and the finished Scene goes through check_scene's
// rules as a last guard (a mesh file's content, transformed values past the float range).
#include <cmath>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>

#include "io/image_io.hpp"
#include "io/json_reader.hpp"
#include "io/path_util.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/scene/check.hpp"
#include "spaceland/scene/mesh_file.hpp"
#include "spaceland/scene/shapes.hpp"
#include "spaceland/scene/transform.hpp"

namespace penumbra::spaceland {
namespace {

using io::Range;
using nlohmann::json;

constexpr const char* kObjectTypes = "one of mesh, box, sphere, quad, disk";
constexpr const char* kVec3 = "an array of 3 numbers";

std::string key_path(const std::string& prefix, const char* key) {
  return prefix.empty() ? std::string(key) : prefix + "." + key;
}

bool is_integer(const json& j, std::int64_t value) {
  if (!j.is_number_integer()) return false;
  return j.is_number_unsigned() ? j.get<std::uint64_t>() == std::uint64_t(value)
                                : j.get<std::int64_t>() == value;
}

// The object's `transform`; `uniform` when its scale is the same along every axis, which keeps
// spheres and disks exact.
struct ObjectTransform {
  Affine affine;
  bool uniform = true;
  float scale = 1;
};

class SceneReader : public io::JsonReader {
 public:
  SceneReader(const std::string& file, const LoadOptions& options)
      : JsonReader(file), options_(options), base_(std::filesystem::path(file).parent_path()) {}

  Scene read(const json& doc) {
    scene_.source = file();
    if (!doc.is_object()) expected("(document)", "a JSON object", doc);
    // The version first: a document of another version may have other keys.
    const json& version = require(doc, "", "penumbra", "the format version 1");
    if (!version.is_number_integer())
      expected("penumbra", "the format version, the integer 1", version);
    if (!is_integer(version, 1))
      fail_at("penumbra", "unknown version, expected 1, found " + version.dump());
    const json& dims =
        require(doc, "", "dimensions", "the integer 3 (a document without it is a 2D scene)");
    if (!is_integer(dims, 3)) expected("dimensions", "the integer 3 (a 3D scene)", dims);

    check_keys(doc, "",
               {"penumbra", "dimensions", "camera", "sky", "sun", "materials", "objects", "media"});
    read_camera(require(doc, "", "camera", "an object"));
    if (doc.contains("sky")) read_sky(doc["sky"]);
    if (doc.contains("sun")) read_sun(doc["sun"]);
    if (doc.contains("materials")) read_materials(doc["materials"]);
    if (doc.contains("objects")) {
      const json& objects = doc["objects"];
      if (!objects.is_array()) expected("objects", "an array of objects", objects);
      // How many objects use each mesh file: its parse is kept until the last one.
      for (const json& o : objects)
        if (o.is_object() && o.contains("type") && o["type"] == "mesh" && o.contains("file") &&
            o["file"].is_string())
          ++uses_[mesh_key(o["file"].get<std::string>())];
      for (std::size_t i = 0; i < objects.size(); ++i)
        read_object(objects[i], "objects[" + std::to_string(i) + "]");
    }
    if (doc.contains("media")) {
      const json& media = doc["media"];
      if (!media.is_array()) expected("media", "an array of media", media);
      for (std::size_t i = 0; i < media.size(); ++i)
        read_medium(media[i], "media[" + std::to_string(i) + "]");
    }
    check_scene_or_throw(scene_);
    return std::move(scene_);
  }

 private:
  const json& object_at(const json& j, const std::string& path, const std::string& what) const {
    if (!j.is_object()) expected(path, what, j);
    return j;
  }

  Vec3 vec3(const json& j, const std::string& path, Range r = Range::any) const {
    std::string what = kVec3;
    if (r == Range::positive) what += " > 0";
    if (!j.is_array() || j.size() != 3) expected(path, what, j);
    return {number(j[0], path + "[0]", r), number(j[1], path + "[1]", r),
            number(j[2], path + "[2]", r)};
  }
  Vec3 required_vec3(const json& obj, const std::string& prefix, const char* key,
                     Range r = Range::any) const {
    const std::string what = std::string(kVec3) + (r == Range::positive ? " > 0" : "");
    return vec3(require(obj, prefix, key, what), key_path(prefix, key), r);
  }
  // A direction of any non-zero length, normalised.
  Vec3 direction(const json& obj, const std::string& prefix, const char* key) const {
    const Vec3 v = required_vec3(obj, prefix, key);
    const double len = std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
    if (!(len > 0))
      fail_at(key_path(prefix, key), "expected a non-zero vector, found " + format_vec3(v));
    return {float(v.x / len), float(v.y / len), float(v.z / len)};
  }
  // A number in (lo, hi) or (lo, hi].
  float number_in(const json& j, const std::string& path, double lo, double hi,
                  bool hi_closed) const {
    const std::string what = "a number in (" + io::format_number(lo) + ", " +
                             io::format_number(hi) + (hi_closed ? "]" : ")");
    if (!j.is_number()) expected(path, what, j);
    const float f = number(j, path, Range::any);
    const double d = j.get<double>();
    for (double v : {d, double(f)})
      if (!(v > lo && (hi_closed ? v <= hi : v < hi))) expected(path, what, j);
    return f;
  }
  // A number (the same in every channel) or an RGB array.
  Rgb grey_or_rgb(const json& j, const std::string& path, Range r) const {
    if (j.is_number()) {
      const float v = number(j, path, r);
      return {v, v, v};
    }
    if (j.is_array()) return rgb(j, path, r);
    expected(path, std::string(io::expected_text(r)) + " or an array of 3 of them", j);
  }

  void read_camera(const json& j) {
    object_at(j, "camera", "an object with position, look_at, up, fov_y, width and height");
    if (j.contains("gltf")) return read_gltf_camera(j);
    check_keys(j, "camera", {"position", "look_at", "up", "fov_y", "width", "height"});
    Camera& c = scene_.camera;
    c.position = required_vec3(j, "camera", "position");
    c.look_at = required_vec3(j, "camera", "look_at");
    if (j.contains("up")) c.up = vec3(j["up"], "camera.up");
    c.fov_y = number_in(require(j, "camera", "fov_y", "a number in (0, 180)"), "camera.fov_y", 0,
                        180, false);
    const std::string side = "an integer in 1.." + std::to_string(kMaxImageSide);
    c.width = integer(require(j, "camera", "width", side), "camera.width", 1, kMaxImageSide);
    c.height = integer(require(j, "camera", "height", side), "camera.height", 1, kMaxImageSide);
    check_camera(file(), c);
  }

  // The camera a glTF file holds: {"gltf": FILE, "index": N (default 0), "width": W,
  // "height": H (default W / the file's aspectRatio), "transform": as an object's}.
  void read_gltf_camera(const json& j) {
    check_keys(j, "camera", {"gltf", "index", "width", "height", "transform"});
    const std::string what = "a glTF file name (.gltf or .glb)";
    const std::string name = string(require(j, "camera", "gltf", what), "camera.gltf", what);
    const std::string ext = io::lowercase_extension(name);
    if (ext != ".gltf" && ext != ".glb") expected("camera.gltf", what, j["gltf"]);
    std::filesystem::path path(name);
    if (path.is_relative()) path = base_ / path;
    const int index = j.contains("index") ? integer(j["index"], "camera.index", 0, 1 << 30) : 0;
    const GltfCamera g = spaceland::read_gltf_camera(path.string(), index, file(), "camera.gltf",
                                                     options_.max_memory);
    const Affine t = read_transform(j, "camera").affine;
    Camera& c = scene_.camera;
    c.position = t.point(g.position);
    c.look_at = c.position + normalize(t.direction(g.forward));
    c.up = normalize(t.direction(g.up));
    c.fov_y = g.fov_y;
    const std::string side = "an integer in 1.." + std::to_string(kMaxImageSide);
    c.width = integer(require(j, "camera", "width", side), "camera.width", 1, kMaxImageSide);
    if (j.contains("height") || !(g.aspect > 0)) {
      c.height =
          integer(require(j, "camera", "height", side + " (the file's camera has no aspectRatio)"),
                  "camera.height", 1, kMaxImageSide);
    } else {
      const double h = std::round(c.width / double(g.aspect));
      if (!(h >= 1 && h <= kMaxImageSide))
        fail_at("camera.width", "the file's aspectRatio " + io::format_number(g.aspect) +
                                    " makes the height " + io::format_number(h) + ", outside 1.." +
                                    std::to_string(kMaxImageSide) + "; give camera.height");
      c.height = int(h);
    }
    check_camera(file(), c);
  }

  void read_sky(const json& j) {
    Sky& s = scene_.sky;
    if (j.is_array()) {
      s.zenith = s.horizon = s.ground = rgb(j, "sky", Range::nonneg);
      return;
    }
    object_at(j, "sky", "an array of 3 numbers >= 0 or an object with zenith, horizon and ground");
    check_keys(j, "sky", {"zenith", "horizon", "ground"});
    const std::string what = "an array of 3 numbers >= 0";
    s.zenith = rgb(require(j, "sky", "zenith", what), "sky.zenith", Range::nonneg);
    s.horizon = rgb(require(j, "sky", "horizon", what), "sky.horizon", Range::nonneg);
    s.ground = rgb(require(j, "sky", "ground", what), "sky.ground", Range::nonneg);
  }

  void read_sun(const json& j) {
    object_at(j, "sun", "an object with direction, irradiance and angular_radius");
    check_keys(j, "sun", {"direction", "irradiance", "angular_radius"});
    Sun& s = scene_.sun;
    s.direction = direction(j, "sun", "direction");
    s.irradiance = rgb(require(j, "sun", "irradiance", "an array of 3 numbers >= 0"),
                       "sun.irradiance", Range::nonneg);
    if (j.contains("angular_radius"))
      s.angular_radius = number_in(j["angular_radius"], "sun.angular_radius", 0, 45, true);
    scene_.has_sun = true;
  }

  Material material_body(const json& j, const std::string& path) const {
    object_at(j, path, "a material object with albedo, emission, metallic and roughness");
    check_keys(j, path, {"albedo", "emission", "metallic", "roughness"});
    Material m;
    if (j.contains("albedo")) m.albedo = rgb(j["albedo"], path + ".albedo", Range::unit);
    if (j.contains("emission")) m.emission = rgb(j["emission"], path + ".emission", Range::nonneg);
    if (j.contains("metallic")) m.metallic = number(j["metallic"], path + ".metallic", Range::unit);
    if (j.contains("roughness"))
      m.roughness = number(j["roughness"], path + ".roughness", Range::unit);
    return m;
  }

  void read_materials(const json& j) {
    object_at(j, "materials", "an object of named materials");
    for (const auto& item : j.items()) {
      if (is_comment_key(item.key())) continue;
      Material m = material_body(item.value(), "materials." + item.key());
      m.name = item.key();
      named_[item.key()] = std::uint32_t(scene_.materials.size());
      scene_.materials.push_back(std::move(m));
    }
  }

  std::uint32_t add_material(Material m) {
    scene_.materials.push_back(std::move(m));
    return std::uint32_t(scene_.materials.size() - 1);
  }

  // The object's `material`: a name, an inline material, or (absent) the default material.
  std::uint32_t object_material(const json& obj, const std::string& prefix) {
    const std::string path = prefix + ".material";
    auto it = obj.find("material");
    if (it == obj.end()) {
      if (default_material_ < 0) {
        Material m;
        m.name = "default";
        default_material_ = int(add_material(std::move(m)));
      }
      return std::uint32_t(default_material_);
    }
    if (it->is_string()) {
      const std::string name = it->get<std::string>();
      auto found = named_.find(name);
      if (found != named_.end()) return found->second;
      std::string names;
      for (const auto& [n, index] : named_) names += (names.empty() ? "" : ", ") + n;
      fail_at(path, "unknown material \"" + name + "\", expected " +
                        (names.empty() ? std::string("a material object (materials is empty)")
                                       : "one of: " + names + " (or a material object)"));
    }
    if (!it->is_object()) expected(path, "a material name or a material object", *it);
    Material m = material_body(*it, path);
    m.name = path;
    return add_material(std::move(m));
  }

  ObjectTransform read_transform(const json& obj, const std::string& prefix) const {
    ObjectTransform t;
    if (!obj.contains("transform")) return t;
    const std::string path = prefix + ".transform";
    const json& j = object_at(obj["transform"], path, "an object with scale, rotate and translate");
    check_keys(j, path, {"scale", "rotate", "translate"});
    Vec3 scale{1, 1, 1}, rotate, translate;
    if (j.contains("scale")) {
      const json& s = j["scale"];
      if (s.is_number()) {
        const float k = number(s, path + ".scale", Range::positive);
        scale = {k, k, k};
      } else if (s.is_array() && s.size() == 3) {
        scale = vec3(s, path + ".scale", Range::positive);
      } else {
        expected(path + ".scale", "a number > 0 or an array of 3 numbers > 0", s);
      }
    }
    if (j.contains("rotate")) rotate = vec3(j["rotate"], path + ".rotate");
    if (j.contains("translate")) translate = vec3(j["translate"], path + ".translate");
    t.affine = Affine::trs(scale, rotate, translate);
    t.uniform = scale.x == scale.y && scale.y == scale.z;
    t.scale = scale.x;
    return t;
  }

  void read_object(const json& j, const std::string& path) {
    object_at(j, path, "an object");
    const std::string types = std::string("an object type, ") + kObjectTypes;
    const json& type_j = require(j, path, "type", types);
    if (!type_j.is_string()) expected(path + ".type", types, type_j);
    const std::string type = type_j.get<std::string>();
    const int index = int(scene_.objects.size());

    if (type == "mesh") {
      check_keys(j, path, {"type", "file", "material", "transform"});
      read_mesh(j, path, index);
    } else if (type == "box") {
      check_keys(j, path, {"type", "center", "size", "rotate", "material", "transform"});
      const Vec3 center = required_vec3(j, path, "center");
      const Vec3 size = required_vec3(j, path, "size", Range::positive);
      Vec3 rotate;
      if (j.contains("rotate")) rotate = vec3(j["rotate"], path + ".rotate");
      const ObjectTransform t = read_transform(j, path);
      // The object's own rotate turns the box about its centre; the transform comes after.
      add_mesh(box_mesh(t.affine * Affine::trs(size, rotate, center)), j, path, index, "box");
    } else if (type == "sphere") {
      check_keys(j, path, {"type", "center", "radius", "material", "transform"});
      const Vec3 center = required_vec3(j, path, "center");
      const float radius = number(require(j, path, "radius", io::expected_text(Range::positive)),
                                  path + ".radius", Range::positive);
      const ObjectTransform t = read_transform(j, path);
      if (t.uniform) {
        Sphere s{t.affine.point(center), radius * t.scale, object_material(j, path), index};
        check_extent(s.center, s.radius, path, "sphere");
        scene_.spheres.push_back(s);
      } else {
        add_mesh(ellipsoid_mesh(center, radius, t.affine), j, path, index, "sphere");
      }
    } else if (type == "quad") {
      check_keys(j, path, {"type", "corner", "u", "v", "material", "transform"});
      const Vec3 corner = required_vec3(j, path, "corner");
      const Vec3 u = required_vec3(j, path, "u"), v = required_vec3(j, path, "v");
      // Parallel (or zero) edges: no area relative to the edges' lengths (in double).
      const double c[3] = {double(u.y) * v.z - double(u.z) * v.y,
                           double(u.z) * v.x - double(u.x) * v.z,
                           double(u.x) * v.y - double(u.y) * v.x};
      const double uu = double(u.x) * u.x + double(u.y) * u.y + double(u.z) * u.z;
      const double vv = double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z;
      if (!(c[0] * c[0] + c[1] * c[1] + c[2] * c[2] > 1e-12 * uu * vv))
        fail_at(path + ".v", "expected a non-zero edge vector not parallel to u = " +
                                 format_vec3(u) + ", found " + format_vec3(v));
      add_mesh(quad_mesh(corner, u, v, read_transform(j, path).affine), j, path, index, "quad");
    } else if (type == "disk") {
      check_keys(j, path, {"type", "center", "normal", "radius", "material", "transform"});
      const Vec3 center = required_vec3(j, path, "center");
      const Vec3 normal = direction(j, path, "normal");
      const float radius = number(require(j, path, "radius", io::expected_text(Range::positive)),
                                  path + ".radius", Range::positive);
      const ObjectTransform t = read_transform(j, path);
      if (t.uniform) {
        Disk d{t.affine.point(center), t.affine.normal(normal), radius * t.scale,
               object_material(j, path), index};
        check_extent(d.center, d.radius, path, "disk");
        scene_.disks.push_back(d);
      } else {
        add_mesh(ellipse_mesh(center, normal, radius, t.affine), j, path, index, "disk");
      }
    } else {
      fail_at(path + ".type", "unknown object type \"" + type + "\", expected " + kObjectTypes);
    }
    scene_.objects.push_back(path + " (" + type + ")");
    check_memory(path);
  }

  void read_mesh(const json& j, const std::string& path, int index) {
    const std::string what = "a mesh file name (.obj, .gltf or .glb)";
    const std::string name = string(require(j, path, "file", what), path + ".file", what);
    const std::string ext = io::lowercase_extension(name);
    if (ext != ".obj" && ext != ".gltf" && ext != ".glb") expected(path + ".file", what, j["file"]);
    std::filesystem::path file_path(name);
    if (file_path.is_relative()) file_path = base_ / file_path;
    const bool has_material = j.contains("material");
    const std::uint32_t material = has_material ? object_material(j, path) : 0;

    // A file is parsed once however many objects use it (kept until its last use, counted
    // against the memory limit meanwhile); each object gets its own copy of the triangles
    // (transformed, the last use takes the parse's), and the file's materials and textures join
    // the scene once.
    const std::string key = mesh_key(name);
    auto found = parsed_.find(key);
    if (found == parsed_.end()) {
      const std::uint64_t used = scene_bytes(scene_) + parsed_bytes_;
      const std::uint64_t room = used < options_.max_memory ? options_.max_memory - used : 0;
      Parsed p{read_mesh_file(file_path.string(), file(), path + ".file", room), 0, false, 0};
      if (p.file.mesh.triangles.empty())
        fail_at(path + ".file", name + ": the file has no triangles");
      for (const std::string& w : p.file.warnings)
        scene_.warnings.push_back(path + ".file: " + name + ": " + w);
      p.bytes = mesh_bytes(p.file.mesh);
      for (const Texture& t : p.file.textures) p.bytes += t.rgb.size() * sizeof(float);
      parsed_bytes_ += p.bytes;
      found = parsed_.emplace(key, std::move(p)).first;
    }
    Parsed& parsed = found->second;
    const bool last = --uses_[key] <= 0;
    if (!last &&
        scene_bytes(scene_) + parsed_bytes_ + mesh_bytes(parsed.file.mesh) > options_.max_memory)
      fail_at(path + ".file", "the scene needs more than the memory limit of " +
                                  io::format_rounded(double(options_.max_memory)) +
                                  " bytes with this object's copy of " + name);
    TriangleMesh mesh = last ? std::move(parsed.file.mesh) : parsed.file.mesh;
    if (has_material) {
      mesh.materials.assign(mesh.triangles.size(), material);
    } else {
      if (!parsed.joined) {
        // The file's materials and textures join the scene's; their indices shift accordingly.
        parsed.material_base = std::uint32_t(scene_.materials.size());
        const int texture_base = int(scene_.textures.size());
        for (Material& m : parsed.file.materials) {
          for (TextureRef* t :
               {&m.albedo_texture, &m.emission_texture, &m.metallic_roughness_texture})
            if (t->index >= 0) t->index += texture_base;
          scene_.materials.push_back(std::move(m));
        }
        for (Texture& t : parsed.file.textures) {
          const std::uint64_t b = t.rgb.size() * sizeof(float);
          parsed.bytes -= b;
          parsed_bytes_ -= b;
          scene_.textures.push_back(std::move(t));
        }
        std::vector<Texture>().swap(parsed.file.textures);
        parsed.joined = true;
      }
      for (std::uint32_t& m : mesh.materials) m += parsed.material_base;
    }
    if (last) {
      parsed_bytes_ -= parsed.bytes;
      parsed_.erase(found);
    }
    transform_mesh(mesh, read_transform(j, path).affine);
    mesh.object = index;
    check_extent(mesh, path, nullptr);
    scene_.meshes.push_back(std::move(mesh));
  }

  void add_mesh(TriangleMesh mesh, const json& j, const std::string& path, int index,
                const char* type) {
    mesh.materials.assign(mesh.triangles.size(), object_material(j, path));
    mesh.object = index;
    check_extent(mesh, path, type);
    scene_.meshes.push_back(std::move(mesh));
  }

  // Within the format's world (a transform can also carry finite coordinates past floats).
  void check_extent(Vec3 p, float radius, const std::string& path, const char* type) const {
    const Vec3 r{radius, radius, radius};
    check_within_world(file(), path, p - r, p + r,
                       std::string("the ") + type + " (after its transform)");
  }
  // `type`: the shape a mesh was made for, or null for a mesh file.
  void check_extent(const TriangleMesh& mesh, const std::string& path, const char* type) const {
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
      const Vec3 p = mesh.positions[i];
      if (inside_world(p)) continue;
      check_within_world(file(), type ? path : path + ".file", p, p,
                         type ? std::string("the ") + type + " (after its transform)"
                              : "vertex " + std::to_string(i) + " (after the transform)");
    }
  }

  // Mesh files are refused as they are read; shapes and the total are checked here.
  void check_memory(const std::string& path) const {
    const std::uint64_t bytes = scene_bytes(scene_);
    if (bytes > options_.max_memory)
      fail_at(path, "the scene needs " + io::format_rounded(double(bytes)) +
                        " bytes up to this object, more than the memory limit of " +
                        io::format_rounded(double(options_.max_memory)) + " bytes");
  }

  void read_medium(const json& j, const std::string& path) {
    object_at(j, path, "a medium object");
    check_keys(j, path, {"type", "center", "size", "rotate", "extinction", "albedo", "emission"});
    if (j.contains("type") && j["type"] != "box")
      fail_at(path + ".type", "unknown medium type " + io::describe(j["type"]) + ", expected box");
    Medium m;
    m.center = required_vec3(j, path, "center");
    m.half_size = required_vec3(j, path, "size", Range::positive) * 0.5f;
    if (j.contains("rotate")) {
      const Affine r = Affine::trs({1, 1, 1}, vec3(j["rotate"], path + ".rotate"), {});
      // The box's axes are the rotation's columns.
      for (int k = 0; k < 3; ++k)
        m.axes[k] = normalize(Vec3{float(r.m[k]), float(r.m[3 + k]), float(r.m[6 + k])});
    }
    m.extinction =
        grey_or_rgb(require(j, path, "extinction", "a number >= 0 or an array of 3 numbers >= 0"),
                    path + ".extinction", Range::nonneg);
    m.albedo = rgb(require(j, path, "albedo", "an array of 3 numbers in [0, 1]"), path + ".albedo",
                   Range::unit);
    if (j.contains("emission")) m.emission = rgb(j["emission"], path + ".emission", Range::nonneg);
    scene_.media.push_back(m);
  }

  // A mesh file as parsed, kept until its last use, and where its materials begin in the
  // scene's once they have joined it.
  struct Parsed {
    MeshFile file;
    std::uint32_t material_base = 0;
    bool joined = false;
    std::uint64_t bytes = 0;  // of its arrays and textures not yet the scene's
  };
  // The key of a mesh file named `name` in the document: its canonical path where it has one.
  std::string mesh_key(const std::string& name) const {
    std::filesystem::path p(name);
    if (p.is_relative()) p = base_ / p;
    std::error_code ec;
    const std::filesystem::path c = std::filesystem::weakly_canonical(p, ec);
    return ec ? p.string() : c.string();
  }
  static std::uint64_t mesh_bytes(const TriangleMesh& m) {
    return m.positions.size() * sizeof(Vec3) + m.normals.size() * sizeof(Vec3) +
           (m.uvs.size() + m.lightmap_uvs.size()) * sizeof(m.uvs[0]) +
           m.triangles.size() * sizeof(m.triangles[0]) + m.materials.size() * sizeof(std::uint32_t);
  }

  const LoadOptions& options_;
  std::filesystem::path base_;
  Scene scene_;
  std::map<std::string, Parsed> parsed_;  // by mesh_key
  std::map<std::string, int> uses_;       // objects still to read of each mesh_key
  std::uint64_t parsed_bytes_ = 0;
  std::map<std::string, std::uint32_t> named_;
  int default_material_ = -1;
};

}  // namespace

Expected<Scene> parse_scene(std::string_view json_text, const std::string& path,
                            const LoadOptions& options) {
  try {
    const json doc = io::parse_json(json_text, path);
    return SceneReader(path, options).read(doc);
  } catch (const io::JsonFailure& f) {
    return Error{f.message};
  } catch (const std::exception& e) {  // e.g. allocation failure: still no throw across the API
    return Error{path + ": " + e.what()};
  }
}

Expected<Scene> load_scene(const std::string& path, const LoadOptions& options) {
  // The parsed document takes up to about 24 bytes per byte of text (a 16-byte value for a
  // one-digit number, an allocation for each empty array): refused before it is read.
  constexpr std::uint64_t kDocumentBytesPerByte = 24;
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec)) {
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && double(size) * kDocumentBytesPerByte > double(options.max_memory))
      return Error{path + ": the scene file has " + std::to_string(size) +
                   " bytes; parsing it may take " + std::to_string(kDocumentBytesPerByte) +
                   " times that, more than the `max_memory` limit of " +
                   io::format_rounded(double(options.max_memory)) + " bytes"};
  }
  Expected<std::string> text = io::read_text(path, "the scene file");
  if (!text) return text.error();
  return parse_scene(*text, path, options);
}

Expected<int> scene_dimensions(const std::string& path) {
  Expected<std::string> text = io::read_text(path, "the scene file");
  if (!text) return text.error();
  try {
    const json doc = io::parse_json(*text, path);
    const io::JsonReader reader(path);
    if (!doc.is_object()) reader.expected("(document)", "a JSON object", doc);
    auto it = doc.find("dimensions");
    if (it == doc.end()) {
      // A 3D document that forgot `dimensions` would otherwise fail as a 2D one, on "unknown
      // key camera": say what is missing instead.
      std::string keys;
      for (const char* k : {"camera", "objects"})
        if (doc.contains(k)) keys += std::string(keys.empty() ? "" : " and ") + "`" + k + "`";
      if (!keys.empty())
        return Error{path + ": dimensions: missing, but the document has " + keys +
                     ", which only 3D scenes have: add \"dimensions\": 3 (a document without "
                     "it is a 2D scene)"};
      return 2;
    }
    if (is_integer(*it, 2)) return 2;
    if (is_integer(*it, 3)) return 3;
    reader.expected("dimensions", "the integer 2 or 3", *it);
  } catch (const io::JsonFailure& f) {
    return Error{f.message};
  }
}

}  // namespace penumbra::spaceland
