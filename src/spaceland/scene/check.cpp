// Checking scenes built in code, their bounds and their size in bytes.
#include "spaceland/scene/check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "core/d3.hpp"
#include "io/json_reader.hpp"

namespace penumbra::spaceland {

namespace {

using io::expected_text;
using io::fail;
using io::format_number;
using io::in_range;
using io::Range;

// Unit vectors written by readers and by code are normalised in float; a little slack.
constexpr double kUnitTolerance = 1e-3;

std::string item(const std::string& array, std::size_t i) {
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "[" + ... + "]".
  std::string s = array;
  s += '[';
  s += std::to_string(i);
  s += ']';
  return s;
}

void check_float(const std::string& file, const std::string& path, float v, Range r) {
  if (!std::isfinite(v)) fail(file, path, "expected a finite number, found " + format_number(v));
  if (!in_range(v, r))
    fail(file, path, std::string("expected ") + expected_text(r) + ", found " + format_number(v));
}

void check_vec3(const std::string& file, const std::string& path, Vec3 v) {
  for (int k = 0; k < 3; ++k) check_float(file, item(path, k), v[k], Range::any);
}

void check_rgb(const std::string& file, const std::string& path, const Rgb& c, Range r) {
  check_float(file, item(path, 0), c.r, r);
  check_float(file, item(path, 1), c.g, r);
  check_float(file, item(path, 2), c.b, r);
}

double length_d(Vec3 v) {
  return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
}

void check_unit(const std::string& file, const std::string& path, Vec3 v) {
  check_vec3(file, path, v);
  const double len = length_d(v);
  if (std::fabs(len - 1) > kUnitTolerance)
    fail(
        file, path,
        "expected a unit vector, found " + format_vec3(v) + " (length " + format_number(len) + ")");
}

void check_open_interval(const std::string& file, const std::string& path, float v, double lo,
                         double hi, bool hi_closed) {
  const bool ok = std::isfinite(v) && v > lo && (hi_closed ? v <= hi : v < hi);
  if (!ok)
    fail(file, path,
         "expected a number in (" + format_number(lo) + ", " + format_number(hi) +
             (hi_closed ? "]" : ")") + ", found " + format_number(v));
}

void check_material_index(const std::string& file, const std::string& path, std::uint32_t m,
                          const Scene& s) {
  if (m >= s.materials.size())
    fail(file, path,
         "material " + std::to_string(m) + " out of range (" + std::to_string(s.materials.size()) +
             " materials)");
}

void check_object_index(const std::string& file, const std::string& path, int object,
                        const Scene& s) {
  if (object < -1 || (object >= 0 && std::size_t(object) >= s.objects.size()))
    fail(file, path + ".object",
         "object " + std::to_string(object) + " out of range (-1 or one of the " +
             std::to_string(s.objects.size()) + " objects)");
}

// The document's path of an object ("objects[2]") from its line in Scene::objects, or `fallback`
// (a scene built in code).
std::string object_path(const Scene& s, int object, const std::string& fallback) {
  if (object < 0 || std::size_t(object) >= s.objects.size()) return fallback;
  const std::string& line = s.objects[std::size_t(object)];
  return line.substr(0, line.find(" ("));
}

void check_mesh(const std::string& file, const std::string& path, const TriangleMesh& m,
                const Scene& s) {
  const std::size_t n = m.positions.size();
  // A document's mesh is named by its object and the vertex ("objects[3].file: the normal of
  // vertex 0 ..."), a mesh built in code by its arrays ("meshes[3].normals[0][1]"). Messages are
  // made only for a failure: meshes have millions of vertices.
  const bool document = m.object >= 0 && std::size_t(m.object) < s.objects.size();
  const std::string obj =
      document
          ? object_path(s, m.object, path) +
                (s.objects[std::size_t(m.object)].find("(mesh") != std::string::npos ? ".file" : "")
          : std::string();
  auto finite3 = [](Vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
  };
  auto not_finite = [&](const char* what, std::size_t i, Vec3 v) {
    fail(file, obj,
         what + std::to_string(i) + " is not finite: " + format_vec3(v) +
             " (a value of the mesh file, after the object's transform)");
  };
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 p = m.positions[i];
    if (!finite3(p)) {
      if (document) not_finite("vertex ", i, p);
      check_vec3(file, item(path + ".positions", i), p);
    }
    if (!inside_world(p))
      check_within_world(file, object_path(s, m.object, path), p, p,
                         "vertex " + std::to_string(i) + " (in world space)");
  }
  if (!m.normals.empty() && m.normals.size() != n)
    fail(file, path + ".normals",
         "expected none or one per position (" + std::to_string(n) + "), found " +
             std::to_string(m.normals.size()));
  for (std::size_t i = 0; i < m.normals.size(); ++i) {
    const Vec3 v = m.normals[i];
    if (finite3(v) && std::fabs(length_d(v) - 1) <= kUnitTolerance) continue;
    if (!document) check_unit(file, item(path + ".normals", i), v);
    if (!finite3(v)) not_finite("the normal of vertex ", i, v);
    fail(file, obj,
         "the normal of vertex " + std::to_string(i) + " is not a unit vector: " + format_vec3(v));
  }
  // A set of texture coordinates: none or one per position, finite.
  const auto check_uvs = [&](const std::vector<std::array<float, 2>>& uvs, const char* field,
                             const char* what) {
    const std::string at = path + "." + field;
    if (!uvs.empty() && uvs.size() != n)
      fail(file, at,
           "expected none or one per position (" + std::to_string(n) + "), found " +
               std::to_string(uvs.size()));
    for (std::size_t i = 0; i < uvs.size(); ++i) {
      if (std::isfinite(uvs[i][0]) && std::isfinite(uvs[i][1])) continue;
      if (document)
        fail(file, obj,
             std::string("the ") + what + " of vertex " + std::to_string(i) + " are not finite: [" +
                 format_number(uvs[i][0]) + ", " + format_number(uvs[i][1]) + "]");
      check_float(file, item(item(at, i), 0), uvs[i][0], Range::any);
      check_float(file, item(item(at, i), 1), uvs[i][1], Range::any);
    }
  };
  check_uvs(m.uvs, "uvs", "texture coordinates");
  check_uvs(m.lightmap_uvs, "lightmap_uvs", "lightmap coordinates");
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    for (std::uint32_t index : m.triangles[t]) {
      if (index >= n)
        fail(file, item(path + ".triangles", t),
             "index " + std::to_string(index) + " out of range (" + std::to_string(n) +
                 " positions)");
    }
  }
  if (m.materials.size() != m.triangles.size())
    fail(file, path + ".materials",
         "expected one per triangle (" + std::to_string(m.triangles.size()) + "), found " +
             std::to_string(m.materials.size()));
  for (std::size_t t = 0; t < m.materials.size(); ++t)
    if (m.materials[t] >= s.materials.size())
      check_material_index(file, item(path + ".materials", t), m.materials[t], s);
  // A texture sampled through the second set needs the mesh to have it (materials are checked
  // before meshes, so their indices are in range here).
  if (m.lightmap_uvs.empty())
    for (std::size_t t = 0; t < m.materials.size(); ++t) {
      const Material& mat = s.materials[m.materials[t]];
      for (const TextureRef* r :
           {&mat.albedo_texture, &mat.emission_texture, &mat.metallic_roughness_texture})
        if (r->index >= 0 && r->uv_set == 1)
          fail(file, document ? obj : item(path + ".materials", t),
               "material '" + mat.name +
                   "' samples a texture through the second set of texture coordinates, which "
                   "the mesh does not have");
    }
  check_object_index(file, path, m.object, s);
}

void check_texture(const std::string& file, const std::string& path, const Texture& t) {
  if (t.width < 1 || t.height < 1)
    fail(file, path,
         "expected a size of at least 1x1, found " + std::to_string(t.width) + "x" +
             std::to_string(t.height));
  const std::size_t n = std::size_t(t.width) * std::size_t(t.height) * 3;
  if (t.rgb.size() != n)
    fail(file, path + ".rgb",
         "expected " + std::to_string(n) + " values (" + std::to_string(t.width) + "x" +
             std::to_string(t.height) + " RGB), found " + std::to_string(t.rgb.size()));
  // Texels multiply the albedo, so they are reflectances too.
  for (std::size_t i = 0; i < n; ++i)
    check_float(file, item(path + ".rgb", i), t.rgb[i], Range::unit);
}

// What spheres and disks share: centre, radius, material and object.
template <class Shape>
void check_analytic(const std::string& file, const std::string& path, const Shape& shape,
                    const Scene& s) {
  check_vec3(file, path + ".center", shape.center);
  check_float(file, path + ".radius", shape.radius, Range::positive);
  const Vec3 r{shape.radius, shape.radius, shape.radius};
  check_within_world(file, object_path(s, shape.object, path), shape.center - r, shape.center + r,
                     "the shape");
  check_material_index(file, path + ".material", shape.material, s);
  check_object_index(file, path, shape.object, s);
}

}  // namespace

std::string format_vec3(Vec3 v) {
  std::string s = "[";  // piece by piece, for GCC 12's false -Wrestrict
  s += format_number(v.x);
  s += ", ";
  s += format_number(v.y);
  s += ", ";
  s += format_number(v.z);
  s += ']';
  return s;
}

void check_within_world(const std::string& file, const std::string& path, Vec3 lo, Vec3 hi,
                        const std::string& what) {
  for (int k = 0; k < 3; ++k) {
    for (float v : {lo[k], hi[k]}) {
      if (std::fabs(v) <= kMaxCoordinate) continue;  // false for NaN too
      const char axis[2] = {char('x' + k), 0};
      fail(file, path,
           what + " reaches " + axis + " = " + format_number(v) +
               ", past the largest world coordinate the format allows (" +
               format_number(kMaxCoordinate) +
               " in magnitude, so that rays and squared distances stay within floats)");
    }
  }
}

void check_camera(const std::string& file, const Camera& c) {
  check_vec3(file, "camera.position", c.position);
  check_vec3(file, "camera.look_at", c.look_at);
  check_within_world(file, "camera.position", c.position, c.position, "the camera");
  check_within_world(file, "camera.look_at", c.look_at, c.look_at, "the point looked at");
  check_vec3(file, "camera.up", c.up);
  check_open_interval(file, "camera.fov_y", c.fov_y, 0, 180, false);
  for (auto [name, side] :
       {std::pair{"camera.width", c.width}, std::pair{"camera.height", c.height}})
    if (side < 1 || side > kMaxImageSide)
      fail(file, name,
           "expected an integer in 1.." + std::to_string(kMaxImageSide) + ", found " +
               std::to_string(side));
  // In double, as CameraRays finds its basis: float differences of nearby points may underflow.
  const D3 f = d3(c.look_at) - d3(c.position);
  if (!(dot(f, f) > 0))
    fail(file, "camera.look_at",
         "expected a point distinct from camera.position, found " + format_vec3(c.look_at));
  const D3 u = d3(c.up);
  const bool ulen = dot(u, u) > 0;
  const D3 x = ulen ? cross(normalize_scaled(f), normalize_scaled(u)) : D3{0, 0, 0};
  const double sine = std::sqrt(dot(x, x));
  if (!ulen || !(sine > 1e-6))
    fail(file, "camera.up",
         "expected a non-zero vector not parallel to the view direction (look_at - position), "
         "found " +
             format_vec3(c.up));
}

void check_scene_or_throw(const Scene& s) {
  const std::string& file = s.source;
  check_camera(file, s.camera);
  check_rgb(file, "sky.zenith", s.sky.zenith, Range::nonneg);
  check_rgb(file, "sky.horizon", s.sky.horizon, Range::nonneg);
  check_rgb(file, "sky.ground", s.sky.ground, Range::nonneg);
  if (s.has_sun) {
    check_unit(file, "sun.direction", s.sun.direction);
    check_rgb(file, "sun.irradiance", s.sun.irradiance, Range::nonneg);
    check_open_interval(file, "sun.angular_radius", s.sun.angular_radius, 0, 45, true);
  }
  for (std::size_t i = 0; i < s.materials.size(); ++i) {
    const Material& m = s.materials[i];
    const std::string path = item("materials", i);
    check_rgb(file, path + ".albedo", m.albedo, Range::unit);
    check_rgb(file, path + ".emission", m.emission, Range::nonneg);
    check_float(file, path + ".metallic", m.metallic, Range::unit);
    check_float(file, path + ".roughness", m.roughness, Range::unit);
    for (const auto& [name, t] :
         {std::pair{".albedo_texture", &m.albedo_texture},
          std::pair{".emission_texture", &m.emission_texture},
          std::pair{".metallic_roughness_texture", &m.metallic_roughness_texture}}) {
      const std::string at = path + name;
      if (t->index < -1 || (t->index >= 0 && std::size_t(t->index) >= s.textures.size()))
        fail(file, at + ".index",
             "texture " + std::to_string(t->index) + " out of range (-1 or one of the " +
                 std::to_string(s.textures.size()) + " textures)");
      if (t->uv_set != 0 && t->uv_set != 1)
        fail(file, at + ".uv_set", "expected 0 or 1, found " + std::to_string(t->uv_set));
      for (std::size_t k = 0; k < t->transform.size(); ++k)
        check_float(file, item(at + ".transform", k), t->transform[k], Range::any);
    }
  }
  for (std::size_t i = 0; i < s.textures.size(); ++i)
    check_texture(file, item("textures", i), s.textures[i]);
  for (std::size_t i = 0; i < s.meshes.size(); ++i)
    check_mesh(file, item("meshes", i), s.meshes[i], s);
  for (std::size_t i = 0; i < s.spheres.size(); ++i)
    check_analytic(file, item("spheres", i), s.spheres[i], s);
  for (std::size_t i = 0; i < s.disks.size(); ++i) {
    check_analytic(file, item("disks", i), s.disks[i], s);
    check_unit(file, item("disks", i) + ".normal", s.disks[i].normal);
  }
  for (std::size_t i = 0; i < s.media.size(); ++i) {
    const Medium& m = s.media[i];
    const std::string path = item("media", i);
    check_vec3(file, path + ".center", m.center);
    for (int k = 0; k < 3; ++k) {
      check_float(file, item(path + ".half_size", k), m.half_size[k], Range::positive);
      check_unit(file, item(path + ".axes", k), m.axes[k]);
    }
    // The box's reach along each world axis: its half sizes along its axes, projected.
    Vec3 reach;
    for (int w = 0; w < 3; ++w)
      for (int k = 0; k < 3; ++k) reach[w] += m.half_size[k] * std::fabs(m.axes[k][w]);
    check_within_world(file, path, m.center - reach, m.center + reach, "the fog box");
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3;
      const double d = double(m.axes[a].x) * m.axes[b].x + double(m.axes[a].y) * m.axes[b].y +
                       double(m.axes[a].z) * m.axes[b].z;
      if (std::fabs(d) > kUnitTolerance)
        fail(file, path + ".axes",
             "expected orthogonal axes, found axes " + std::to_string(a) + " and " +
                 std::to_string(b) + " with dot product " + format_number(d));
    }
    check_rgb(file, path + ".extinction", m.extinction, Range::nonneg);
    check_rgb(file, path + ".albedo", m.albedo, Range::unit);
    check_rgb(file, path + ".emission", m.emission, Range::nonneg);
  }
}

Status check_scene(const Scene& scene) {
  try {
    check_scene_or_throw(scene);
  } catch (const io::JsonFailure& f) {
    return Error{f.message};
  }
  return {};
}

Bounds scene_bounds(const Scene& s) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  Vec3 lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  for (const TriangleMesh& m : s.meshes) {
    for (Vec3 p : m.positions) {
      lo = min(lo, p);
      hi = max(hi, p);
    }
  }
  for (const Sphere& sp : s.spheres) {
    const Vec3 r{sp.radius, sp.radius, sp.radius};
    lo = min(lo, sp.center - r);
    hi = max(hi, sp.center + r);
  }
  for (const Disk& d : s.disks) {
    // The disk's extent along axis i is radius * sin(angle between the normal and the axis).
    Vec3 e;
    for (int k = 0; k < 3; ++k)
      e[k] = d.radius * std::sqrt(std::max(0.0f, 1 - d.normal[k] * d.normal[k]));
    lo = min(lo, d.center - e);
    hi = max(hi, d.center + e);
  }
  if (!(lo.x <= hi.x)) return {};
  return {lo, hi};
}

std::uint64_t scene_bytes(const Scene& s) {
  std::uint64_t bytes = 0;
  for (const TriangleMesh& m : s.meshes)
    bytes += m.positions.size() * sizeof(Vec3) + m.normals.size() * sizeof(Vec3) +
             (m.uvs.size() + m.lightmap_uvs.size()) * sizeof(m.uvs[0]) +
             m.triangles.size() * sizeof(m.triangles[0]) +
             m.materials.size() * sizeof(std::uint32_t);
  for (const Texture& t : s.textures) bytes += t.rgb.size() * sizeof(float);
  bytes += s.spheres.size() * sizeof(Sphere) + s.disks.size() * sizeof(Disk) +
           s.media.size() * sizeof(Medium) + s.materials.size() * sizeof(Material);
  return bytes;
}

}  // namespace penumbra::spaceland
