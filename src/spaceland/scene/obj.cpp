// OBJ + MTL through tinyobjloader. The text is checked first for what tinyobjloader lets pass
// silently (it reads "nan" as 0, skips quads whose indices are out of range, drops faces of fewer
// than 3 corners), then parsed, then de-indexed: OBJ indexes positions, normals and uvs apart, a
// TriangleMesh has one normal and uv per position.
#include <tiny_obj_loader.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>
#include <string_view>
#include <tuple>
#include <unordered_map>

#include "io/json_reader.hpp"
#include "spaceland/scene/mesh_reader.hpp"
#include "spaceland/scene/polygon.hpp"

namespace penumbra::spaceland::mesh_detail {

namespace {

std::string line_at(std::size_t line) {
  return "line " + std::to_string(line);
}

// The next token of `s` from `pos` (split on blanks), empty at the end.
std::string_view next_token(std::string_view s, std::size_t& pos) {
  while (pos < s.size() && (s[pos] == ' ' || s[pos] == '\t' || s[pos] == '\r')) ++pos;
  const std::size_t start = pos;
  while (pos < s.size() && s[pos] != ' ' && s[pos] != '\t' && s[pos] != '\r') ++pos;
  return s.substr(start, pos - start);
}

// A finite number as written, or a failure naming `where`.
double finite_number(std::string_view token, const std::string& where) {
  std::string_view t = token;
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  double v = 0;
  const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  if (r.ec != std::errc() || r.ptr != t.data() + t.size() || !std::isfinite(v))
    mesh_fail(where + ": '" + std::string(token) + "' is not a finite number");
  // Read as a float: 1e39 would become infinite.
  if (std::fabs(v) > double(std::numeric_limits<float>::max()))
    mesh_fail(where + ": '" + std::string(token) + "' is past the float range (3.4e+38)");
  return v;
}

// Every number after the keywords in `numeric` must be finite, at least `min_count` of them.
// Faces' indices are checked against the vertex counts: negative ones (relative) against those
// before the line, positive ones against the totals at the end.
// The corners of each face go to `face_sizes` in the file's order (tinyobjloader keeps a face's
// count in a byte).
struct ObjCounts {
  std::uint64_t vertices = 0, uvs = 0, normals = 0;
};

// Of each material of an MTL file (in the order of its named newmtl lines, as tinyobjloader
// stores them), whether it gives Pm and Pr: tinyobjloader reads an absent Pr as 0, a mirror,
// where the format's default is 1.
struct MtlGiven {
  bool metallic = false, roughness = false;
};

void check_text(std::string_view text, const std::string& file, bool obj,
                std::vector<std::uint32_t>* face_sizes = nullptr, ObjCounts* counts = nullptr,
                std::vector<MtlGiven>* given = nullptr) {
  struct Kind {
    long long count = 0, max_index = 0;
    std::size_t max_line = 0;
    const char* name;
  };
  Kind kinds[3] = {{0, 0, 0, "vertex"}, {0, 0, 0, "texture coordinate"}, {0, 0, 0, "normal"}};
  // What precedes the first named newmtl: tinyobjloader keeps it as a nameless material only
  // where no named one follows.
  MtlGiven initial;
  std::size_t line = 0, begin = 0;
  while (begin < text.size()) {
    // Lines end at \n, \r\n or \r, as tinyobjloader's do.
    std::size_t end = text.find_first_of("\n\r", begin);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view l = text.substr(begin, end - begin);
    begin = end + (end + 1 < text.size() && text[end] == '\r' && text[end + 1] == '\n' ? 2 : 1);
    ++line;
    std::size_t pos = 0;
    const std::string_view key = next_token(l, pos);
    int min_count = -1, kind = -1;
    if (obj) {
      if (key == "v") min_count = 3, kind = 0;
      if (key == "vt") min_count = 1, kind = 1;
      if (key == "vn") min_count = 3, kind = 2;
    } else if (key == "Kd" || key == "Ke") {
      min_count = 3;
    } else if (key == "Pr" || key == "Pm") {
      min_count = 1;
      if (given) {
        MtlGiven& g = given->empty() ? initial : given->back();
        (key == "Pr" ? g.roughness : g.metallic) = true;
      }
    } else if (key == "newmtl" && given) {
      std::size_t after = pos;
      if (!next_token(l, after).empty()) given->emplace_back();  // a nameless one is skipped
    }
    const std::string where = file + " " + line_at(line);
    if (min_count > 0) {
      int n = 0;
      for (std::string_view t = next_token(l, pos); !t.empty(); t = next_token(l, pos), ++n)
        finite_number(t, where);
      if (n < min_count)
        mesh_fail(where + ": '" + std::string(key) + "' needs " + std::to_string(min_count) +
                  " numbers");
      if (kind >= 0) ++kinds[kind].count;
    } else if (obj && key == "f") {
      int corners = 0;
      for (std::string_view t = next_token(l, pos); !t.empty(); t = next_token(l, pos), ++corners) {
        for (int k = 0; k < 3 && !t.empty(); ++k) {
          const std::size_t slash = t.find('/');
          const std::string_view part = t.substr(0, slash);
          t = slash == std::string_view::npos ? std::string_view() : t.substr(slash + 1);
          if (part.empty()) continue;
          long long idx = 0;
          const auto r = std::from_chars(part.data(), part.data() + part.size(), idx);
          if (r.ec != std::errc() || r.ptr != part.data() + part.size() || idx == 0)
            mesh_fail(where + ": '" + std::string(part) + "' is not a valid " + kinds[k].name +
                      " index (1-based, or negative from the end)");
          if (idx < 0 && -idx > kinds[k].count)
            mesh_fail(where + ": " + kinds[k].name + " index " + std::string(part) +
                      " out of range (" + std::to_string(kinds[k].count) + " before it)");
          if (idx > kinds[k].max_index) kinds[k].max_index = idx, kinds[k].max_line = line;
        }
      }
      if (corners < 3) mesh_fail(where + ": a face needs at least 3 corners");
      if (face_sizes) face_sizes->push_back(std::uint32_t(corners));
    }
  }
  if (given && given->empty()) given->push_back(initial);
  if (counts)
    *counts = {std::uint64_t(kinds[0].count), std::uint64_t(kinds[1].count),
               std::uint64_t(kinds[2].count)};
  for (const Kind& k : kinds)
    if (k.max_index > k.count)
      mesh_fail(file + " " + line_at(k.max_line) + ": " + k.name + " index " +
                std::to_string(k.max_index) + " out of range (" + std::to_string(k.count) +
                " in the file)");
}

// Opens MTL files next to the OBJ file, checks their numbers, and remembers which file each
// material came from. A missing MTL file is refused (its materials would silently vanish).
class MtlReader : public tinyobj::MaterialReader {
 public:
  MtlReader(std::filesystem::path dir, Budget& budget) : dir_(std::move(dir)), budget_(budget) {}
  bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                  std::map<std::string, int>* map, std::string* warn, std::string* err) override {
    const std::string text =
        read_whole_file((dir_ / name).string(), budget_.max(), "MTL file '" + name + "' (mtllib)");
    std::vector<MtlGiven> found;
    check_text(text, name, false, nullptr, nullptr, &found);
    std::istringstream in(text);
    const std::size_t before = materials->size();
    tinyobj::LoadMtl(map, materials, &in, warn, err);
    files.resize(materials->size(), name);
    if (materials->size() - before != found.size())
      mesh_fail(name + ": " + std::to_string(found.size()) + " named materials, of which " +
                "tinyobjloader read " + std::to_string(materials->size() - before));
    given.insert(given.end(), found.begin(), found.end());
    return true;
  }
  std::vector<std::string> files;  // the MTL file of each material
  std::vector<MtlGiven> given;     // whether each material gives Pm and Pr

 private:
  std::filesystem::path dir_;
  Budget& budget_;
};

Material named_material(std::string name) {
  Material m;
  m.name = std::move(name);
  return m;
}

Material convert(const tinyobj::material_t& m, const std::string& file, MtlGiven given) {
  Material out;
  out.name = m.name;
  const std::string what = "material '" + m.name + "' in " + file;
  for (int c = 0; c < 3; ++c) {
    const float kd = float(m.diffuse[c]), ke = float(m.emission[c]);
    if (!(kd >= 0 && kd <= 1))
      mesh_fail(what + ": Kd " + io::format_number(kd) + " is outside [0, 1]");
    if (!(ke >= 0) || !std::isfinite(ke))
      mesh_fail(what + ": Ke " + io::format_number(ke) + " must be a finite number >= 0");
  }
  out.albedo = {float(m.diffuse[0]), float(m.diffuse[1]), float(m.diffuse[2])};
  out.emission = {float(m.emission[0]), float(m.emission[1]), float(m.emission[2])};
  // PBR extension of MTL: Pm (metallic) and Pr (roughness), where given.
  for (const auto& [key, value, is_given, field] :
       {std::tuple{"Pm", m.metallic, given.metallic, &out.metallic},
        std::tuple{"Pr", m.roughness, given.roughness, &out.roughness}}) {
    if (!is_given) continue;
    if (!(value >= 0 && value <= 1))
      mesh_fail(what + ": " + key + " " + io::format_number(value) + " is outside [0, 1]");
    *field = float(value);
  }
  return out;
}

// The images of map_Kd and map_Ke (sRGB-encoded colours), read once each; `name` is relative to
// the OBJ file. Of their options, -o and -s (offset and scale) and -clamp change what is drawn; the
// rest (-mm, -bm, -boost, ...) are read by tinyobjloader and left.
class ObjTextures {
 public:
  ObjTextures(std::filesystem::path dir, Budget& budget, std::vector<Texture>& out)
      : dir_(std::move(dir)), budget_(budget), out_(out) {}

  TextureRef load(const std::filesystem::path& file, const tinyobj::texture_option_t& o,
                  const std::string& what) {
    const std::string name = file.generic_string();
    TextureRef ref;
    const auto cached = loaded_.find({name, o.clamp});
    if (cached != loaded_.end()) {
      ref.index = cached->second;
    } else {
      const std::string bytes =
          read_whole_file((dir_ / name).string(), budget_.max(), what + " '" + name + "'");
      budget_.take(bytes.size(), what + " '" + name + "'");
      Texture t = decode_texture(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(),
                                 true, what + " '" + name + "'", budget_);
      if (o.clamp) t.wrap_s = t.wrap_t = Texture::Wrap::clamp;
      out_.push_back(std::move(t));
      ref.index = loaded_[{name, o.clamp}] = int(out_.size() - 1);
    }
    // MTL texture coordinates run up the image, ours down (they are stored as 1 - v): the map
    // (u, v) -> (s u + o) taken in the file's v is s_v v + 1 - s_v - o_v in ours.
    for (int k = 0; k < 2; ++k)
      if (!std::isfinite(o.scale[k]) || !std::isfinite(o.origin_offset[k]))
        mesh_fail(what + ": -s and -o need finite numbers");
    const float su = float(o.scale[0]), sv = float(o.scale[1]);
    const float ou = float(o.origin_offset[0]), ov = float(o.origin_offset[1]);
    ref.transform = {su, 0, ou, 0, sv, 1 - sv - ov};
    return ref;
  }

 private:
  std::filesystem::path dir_;
  Budget& budget_;
  std::vector<Texture>& out_;
  std::map<std::pair<std::string, bool>, int> loaded_;
};

// Ear clipping of a face that is not convex costs its corners times its reflex corners: bounded
// for the whole file, so that hostile faces cost seconds at most.
constexpr std::uint64_t kMaxPolygonSteps = 200'000'000;

struct Corner {
  int v, vt, vn;
  bool operator==(const Corner&) const = default;
};
struct CornerHash {
  std::size_t operator()(const Corner& c) const {
    return std::size_t(c.v) * 0x9E3779B97F4A7C15ull ^ std::size_t(c.vt) * 0xC2B2AE3D27D4EB4Full ^
           std::size_t(c.vn);
  }
};

}  // namespace

MeshFile read_obj(const std::string& path, Budget& budget) {
  const std::string name = std::filesystem::path(path).filename().string();
  const std::string text = read_whole_file(path, budget.max(), "the file");
  budget.take(text.size(), "the file's text");
  std::vector<std::uint32_t> face_sizes;
  ObjCounts counts;
  check_text(text, name, true, &face_sizes, &counts);
  // What tinyobjloader holds while it reads, refused before it starts: a copy of the text (its
  // stream), its arrays (a vertex 16 bytes with its weight, a uv 12, a normal 12, a corner 12 in
  // the shapes and 12 in its face list, a face about 90 with its list's own allocation), and
  // ours after it (the corners' index, 48 bytes a distinct corner, 4 bytes a face count).
  std::uint64_t corners = 0, triangles = 0;
  for (std::uint32_t n : face_sizes) corners += n, triangles += n - 2;  // check_text: n >= 3
  const std::uint64_t faces = face_sizes.size();
  const std::uint64_t distinct =
      std::min<long double>(corners, (long double)std::max<std::uint64_t>(counts.vertices, 1) *
                                         std::max<std::uint64_t>(counts.uvs, 1) *
                                         std::max<std::uint64_t>(counts.normals, 1));
  // Ours at the end: no more vertices than distinct corners, plus those given a triangle's
  // normal where a corner has none.
  // Where the file has normals, a corner without one gets a vertex of its own: up to 3 a
  // triangle.
  budget.take(mesh_bytes(counts.normals > 0 ? 3 * triangles
                                            : std::min<std::uint64_t>(distinct, 3 * triangles),
                         counts.normals > 0, counts.uvs > 0, triangles),
              std::to_string(triangles) + " triangles");
  if (3 * triangles > UINT32_MAX) mesh_fail("more than 2^32 vertices");
  budget.take(
      text.size() + 16 * counts.vertices + 12 * (counts.uvs + counts.normals) + 24 * corners +
          94 * faces + 48 * distinct,
      "reading " + std::to_string(faces) + " faces of " + std::to_string(corners) + " corners");

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> materials;
  std::string warn, err;
  MtlReader mtl(std::filesystem::path(path).parent_path(), budget);
  std::istringstream in(text);
  // Faces as written: tinyobjloader's own triangulation takes time quadratic in a face's corners
  // (25 s for one face of 100,000); triangulate_polygon is linear where the face is convex.
  if (!tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, &mtl, false, false))
    mesh_fail("invalid OBJ: " + err);

  MeshFile out;
  ObjTextures textures(std::filesystem::path(path).parent_path(), budget, out.textures);
  for (std::size_t i = 0; i < materials.size(); ++i) {
    const tinyobj::material_t& m = materials[i];
    Material mat = convert(m, mtl.files[i], mtl.given[i]);
    const std::string what = "material '" + m.name + "' in " + mtl.files[i];
    // Texture files are named relative to their MTL file.
    const std::filesystem::path from = std::filesystem::path(mtl.files[i]).parent_path();
    if (!m.diffuse_texname.empty())
      mat.albedo_texture =
          textures.load(from / m.diffuse_texname, m.diffuse_texopt, what + ": map_Kd");
    if (!m.emissive_texname.empty())
      mat.emission_texture =
          textures.load(from / m.emissive_texname, m.emissive_texopt, what + ": map_Ke");
    for (const auto& [key, name] :
         {std::pair{"map_Pr", &m.roughness_texname}, std::pair{"map_Pm", &m.metallic_texname}})
      if (!name->empty())
        out.warnings.push_back(what + ": " + key +
                               " is not implemented: drawn with Pr and Pm alone");
    out.materials.push_back(std::move(mat));
  }
  int default_material = -1;

  bool any_normals = false, any_uvs = false;
  for (const auto& s : shapes) {
    for (const auto& idx : s.mesh.indices) {
      any_normals |= idx.normal_index >= 0;
      any_uvs |= idx.texcoord_index >= 0;
    }
  }

  TriangleMesh& mesh = out.mesh;
  std::unordered_map<Corner, std::uint32_t, CornerHash> unique;
  const std::size_t nv = attrib.vertices.size() / 3, nn = attrib.normals.size() / 3,
                    nt = attrib.texcoords.size() / 2;
  auto position = [&](int v) {
    return Vec3{attrib.vertices[3 * v], attrib.vertices[3 * v + 1], attrib.vertices[3 * v + 2]};
  };
  std::vector<Vec3> face;
  std::vector<std::array<std::uint32_t, 3>> pieces;
  PolygonWork work;
  std::size_t face_no = 0;
  std::uint64_t steps_left = kMaxPolygonSteps;  // for the whole file
  for (const auto& s : shapes) {
    const auto& face_ids = s.mesh.indices;
    std::size_t first = 0;
    for (std::size_t fi = 0; fi < s.mesh.num_face_vertices.size(); ++fi) {
      // The count as the file has it; tinyobjloader's is kept modulo 256.
      if (face_no >= face_sizes.size() ||
          (face_sizes[face_no] & 0xFF) != s.mesh.num_face_vertices[fi])
        mesh_fail("the faces read differ from the file's 'f' lines (face " +
                  std::to_string(face_no + 1) + ")");
      const std::size_t n = face_sizes[face_no++];
      if (first + n > face_ids.size()) mesh_fail("shape '" + s.name + "': a face is cut short");
      face.clear();
      for (std::size_t k = 0; k < n; ++k) {
        const int v = face_ids[first + k].vertex_index;
        if (v < 0 || std::size_t(v) >= nv)
          mesh_fail("shape '" + s.name + "': an index is out of range");
        face.push_back(position(v));
      }
      pieces.clear();
      const bool done = triangulate_polygon(face, pieces, steps_left, work);
      steps_left -= std::min(steps_left, work.steps);
      if (!done)
        mesh_fail("shape '" + s.name + "': face " + std::to_string(face_no) + ", of " +
                  std::to_string(n) +
                  " corners, not convex: triangulating the file's faces takes more than " +
                  io::format_rounded(double(kMaxPolygonSteps)) +
                  " steps (corners times reflex corners); split them into smaller faces");
      for (const auto& piece : pieces) {
        std::array<std::uint32_t, 3> tri{};
        Corner c[3];
        for (int k = 0; k < 3; ++k) {
          const auto& idx = face_ids[first + piece[k]];
          // check_text has checked the ranges; this guards against a reading that differs.
          if (idx.vertex_index < 0 || std::size_t(idx.vertex_index) >= nv ||
              std::size_t(idx.normal_index + 1) > nn || std::size_t(idx.texcoord_index + 1) > nt)
            mesh_fail("shape '" + s.name + "': an index is out of range");
          c[k] = {idx.vertex_index, idx.texcoord_index, idx.normal_index};
        }
        const Vec3 p[3] = {position(c[0].v), position(c[1].v), position(c[2].v)};
        for (int k = 0; k < 3; ++k) {
          Vec3 n{0, 0, 1};
          bool shared = true;
          if (any_normals) {
            if (c[k].vn >= 0) {
              const float* a = &attrib.normals[3 * c[k].vn];
              n = Vec3{a[0], a[1], a[2]};
            }
            const float len = length(n);
            // A corner without a usable normal gets its triangle's, on a vertex of its own.
            shared = c[k].vn >= 0 && len > 0 && std::isfinite(len);
            n = shared ? n / len : flat_normal(p[0], p[1], p[2]);
          }
          if (shared) {
            const auto [it, added] = unique.try_emplace(c[k], std::uint32_t(mesh.positions.size()));
            tri[k] = it->second;
            if (!added) continue;
          } else {
            tri[k] = std::uint32_t(mesh.positions.size());
          }
          mesh.positions.push_back(p[k]);
          if (any_normals) mesh.normals.push_back(n);
          if (any_uvs) {
            const float* t = c[k].vt >= 0 ? &attrib.texcoords[2 * c[k].vt] : nullptr;
            // OBJ's v runs up the image, the Texture convention's (glTF's) down.
            mesh.uvs.push_back(t ? std::array<float, 2>{t[0], 1 - t[1]}
                                 : std::array<float, 2>{0, 0});
          }
        }
        int m = s.mesh.material_ids[fi];
        if (m < 0 || std::size_t(m) >= out.materials.size()) {
          // Faces without usemtl (or naming no material of the MTL files): albedo 0.8, no emission.
          if (default_material < 0) {
            default_material = int(out.materials.size());
            out.materials.push_back(named_material("default"));
          }
          m = default_material;
        }
        mesh.triangles.push_back(tri);
        mesh.materials.push_back(std::uint32_t(m));
      }
      first += n;
    }
  }
  if (face_no != face_sizes.size()) mesh_fail("the faces read differ from the file's 'f' lines");
  if (out.materials.empty()) out.materials.push_back(named_material("default"));
  return out;
}

}  // namespace penumbra::spaceland::mesh_detail
