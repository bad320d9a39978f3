// Mesh files: OBJ + MTL and glTF 2.0, hand-written fixtures and the Debian test models
// (glmark2-data's bunny, assimp-testmodels' glTF and glTF2 folders), read in place.
#include "spaceland/scene/mesh_file.hpp"

#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "io/image_io.hpp"
#include "io/json_reader.hpp"
#include "test_support.hpp"

namespace penumbra::spaceland {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr std::uint64_t kLimit = std::uint64_t(1) << 30;
const std::string kBunny = "/usr/share/glmark2/models/bunny.obj";
const std::string kGltf2 = "/usr/share/assimp/models/glTF2/";
const std::string kGltf1 = "/usr/share/assimp/models/glTF/";

// A missing Debian model fails the test: the checks must not pass by skipping.
bool have(const std::string& path) {
  if (fs::exists(path)) return true;
  ADD_FAILURE() << path << " is missing: run scripts/install-deps.sh (glmark2-data, "
                << "assimp-testmodels)";
  return false;
}

MeshFile read(const std::string& path, std::uint64_t limit = kLimit) {
  return read_mesh_file(path, "scene.json", "objects[0].file", limit);
}

// The message of the failure reading `path`, or "" (and a test failure) when it loads.
std::string refusal(const std::string& path, std::uint64_t limit = kLimit) {
  try {
    read(path, limit);
  } catch (const io::JsonFailure& e) {
    return e.message;
  }
  ADD_FAILURE() << path << " loaded, expected a refusal";
  return "";
}

MeshFile loads(const std::string& path) {
  try {
    return read(path);
  } catch (const io::JsonFailure& e) {
    ADD_FAILURE() << e.message;
  }
  return {};
}

std::string prefix(const std::string& file) {
  return "scene.json: objects[0].file: " + file + ": ";
}

struct Dir : testing::TestDir {
  Dir() : testing::TestDir("mesh") {}
};

// A 2 x 1 PNG: texel 0 (64, 128, 255), texel 1 (255, 0, 32); returns its path.
std::string two_texels(Dir& d, const std::string& name) {
  const std::string path = (fs::path(d.write(name, "")).string());
  EXPECT_TRUE(io::write_png8(path, 2, 1, {64, 128, 255, 255, 0, 32}).ok());
  return path;
}

double srgb_to_linear(unsigned char c) {
  const double s = c / 255.0;
  return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
}

// ---- OBJ ----

TEST(MeshFileObj, BunnyHasOneTriangleByFaceLine) {
  if (!have(kBunny)) return;
  std::ifstream in(kBunny);
  std::size_t faces = 0, vertices = 0;
  for (std::string line; std::getline(in, line);) {
    faces += line.rfind("f ", 0) == 0;
    vertices += line.rfind("v ", 0) == 0;
  }
  ASSERT_GT(faces, 0u);
  const MeshFile m = loads(kBunny);
  EXPECT_EQ(m.mesh.triangles.size(), faces);
  EXPECT_EQ(m.mesh.positions.size(), vertices);  // no normals or uvs to split vertices
  EXPECT_TRUE(m.mesh.normals.empty());
  ASSERT_EQ(m.materials.size(), 1u);
  EXPECT_FLOAT_EQ(m.materials[0].albedo.g, 0.8f);
  EXPECT_EQ(m.mesh.materials.size(), faces);
}

TEST(MeshFileObj, QuadIsTwoTrianglesWithTheMtlMaterials) {
  Dir d;
  d.write("m.mtl", "newmtl red\nKd 0.9 0.1 0.2\nKe 0 0 0\n\nnewmtl lamp\nKd 0 0 0\nKe 5 4 3\n");
  const std::string obj = d.write("q.OBJ",
                                  "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
                                  "usemtl red\nf 1 2 3 4\nusemtl lamp\nf 1 2 5\n"
                                  "f 2 3 4 5 1\n");
  const MeshFile m = loads(obj);
  ASSERT_EQ(m.mesh.triangles.size(), 2u + 1u + 3u);
  ASSERT_EQ(m.materials.size(), 2u);
  EXPECT_EQ(m.materials[0].name, "red");
  EXPECT_FLOAT_EQ(m.materials[0].albedo.r, 0.9f);
  EXPECT_FLOAT_EQ(m.materials[0].albedo.b, 0.2f);
  EXPECT_FLOAT_EQ(m.materials[1].emission.r, 5);
  EXPECT_FLOAT_EQ(m.materials[1].emission.b, 3);
  EXPECT_EQ(m.materials[1].albedo_texture.index, -1);
  EXPECT_EQ(m.mesh.materials[0], 0u);
  EXPECT_EQ(m.mesh.materials[1], 0u);
  EXPECT_EQ(m.mesh.materials[2], 1u);
  EXPECT_EQ(m.mesh.positions.size(), 5u);
  EXPECT_TRUE(m.mesh.uvs.empty());
}

TEST(MeshFileObj, MtlGivesMetallicRoughnessAndTextures) {
  Dir d;
  two_texels(d, "t.png");
  // Pr and Pm where given (an absent Pr is the format's 1, not tinyobjloader's 0); map_Kd with
  // -s and -o, map_Ke clamped; both read once.
  d.write("m.mtl",
          "newmtl metal\nKd 0.9 0.9 0.9\nPm 1\nPr 0.25\nmap_Kd -s 2 1 1 -o 0.5 0.25 0 t.png\n"
          "newmtl plain\nKd 0.5 0.5 0.5\nPm 0.5\nmap_Kd t.png\nKe 1 1 1\nmap_Ke -clamp on t.png\n"
          "map_Pr rough.png\n");
  const std::string obj =
      d.write("q.obj",
              "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
              "usemtl metal\nf 1/1 2/2 3/3\nusemtl plain\nf 1/1 3/3 2/2\n");
  const MeshFile m = loads(obj);
  ASSERT_EQ(m.materials.size(), 2u);
  EXPECT_EQ(m.materials[0].metallic, 1);
  EXPECT_EQ(m.materials[0].roughness, 0.25f);
  EXPECT_EQ(m.materials[1].metallic, 0.5f);
  EXPECT_EQ(m.materials[1].roughness, 1);
  ASSERT_EQ(m.textures.size(), 2u);  // repeating and clamped
  EXPECT_EQ(m.materials[0].albedo_texture.index, 0);
  EXPECT_EQ(m.materials[1].albedo_texture.index, 0);
  EXPECT_EQ(m.materials[1].emission_texture.index, 1);
  EXPECT_EQ(m.textures[1].wrap_s, Texture::Wrap::clamp);
  EXPECT_NEAR(m.textures[0].rgb[0], srgb_to_linear(64), 1e-6);
  EXPECT_NEAR(m.textures[0].rgb[5], srgb_to_linear(32), 1e-6);
  // In our v (down the image): s_v v + 1 - s_v - o_v.
  const auto& t = m.materials[0].albedo_texture.transform;
  EXPECT_EQ(t, (std::array<float, 6>{2, 0, 0.5f, 0, 1, -0.25f}));
  EXPECT_EQ(m.materials[1].albedo_texture.transform, (std::array<float, 6>{1, 0, 0, 0, 1, 0}));
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_EQ(m.warnings[0],
            "material 'plain' in m.mtl: map_Pr is not implemented: drawn with Pr and Pm alone");

  // Old Mac line endings (\r alone) and a material before any newmtl, as tinyobjloader reads
  // them; a Pr that is not a number is refused, not read as 0 (a mirror).
  d.write("cr.mtl", "newmtl a\rKd 0.5 0.5 0.5\rPr 0.2\rPm 1\rnewmtl b\rKd 0.1 0.1 0.1\r");
  const MeshFile cr = loads(d.write("cr.obj",
                                    "mtllib cr.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl a\nf 1 2 3\n"
                                    "usemtl b\nf 1 3 2\n"));
  ASSERT_EQ(cr.materials.size(), 2u);
  EXPECT_EQ(cr.materials[0].roughness, 0.2f);
  EXPECT_EQ(cr.materials[0].metallic, 1);
  EXPECT_EQ(cr.materials[1].roughness, 1);
  d.write("none.mtl", "Kd 0.5 0.5 0.5\nPr 0.5\n");
  const MeshFile none =
      loads(d.write("none.obj", "mtllib none.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n"));
  ASSERT_FALSE(none.materials.empty());
  d.write("nan.mtl", "newmtl m\nPr abc\n");
  const std::string nan = d.write("n.obj", "mtllib nan.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
  EXPECT_EQ(refusal(nan), prefix("n.obj") + "nan.mtl line 2: 'abc' is not a finite number");

  d.write("bad.mtl", "newmtl m\nKd 0.5 0.5 0.5\nPr 1.5\n");
  const std::string bad = d.write("b.obj", "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
  EXPECT_EQ(refusal(bad), prefix("b.obj") + "material 'm' in bad.mtl: Pr 1.5 is outside [0, 1]");
  d.write("gone.mtl", "newmtl m\nmap_Kd gone.png\n");
  const std::string gone =
      d.write("g.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
  const std::string msg = refusal(gone);
  EXPECT_NE(msg.find("material 'm' in gone.mtl: map_Kd 'gone.png' not found"), std::string::npos)
      << msg;
}

// A face of more corners than tinyobjloader's byte counts (it kept 100,000 as 160), between two
// small faces of other materials: read from the file's lines, triangulated in linear time (it
// took 25 s), materials kept per face.
TEST(MeshFileObj, FacesOfManyCornersAreReadWhole) {
  Dir d;
  d.write("m.mtl", "newmtl a\nKd 0.1 0.1 0.1\nnewmtl b\nKd 0.2 0.2 0.2\n");
  std::string text = "mtllib m.mtl\n";
  const int n = 100000;
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "v " + std::to_string(...).
  auto add = [&text](auto v) {  // an int stays an integer ("7", not "7.000000")
    text += ' ';
    text += std::to_string(v);
  };
  for (int i = 0; i < n; ++i) {
    text += 'v';
    add(std::cos(2 * M_PI * i / n));
    add(std::sin(2 * M_PI * i / n));
    text += " 0\n";
  }
  text += "usemtl a\r\nf 1 2 3\r\nusemtl b\nf";
  for (int i = 1; i <= n; ++i) add(i);
  text += "\nusemtl a\nf 3 4 5 6\n";
  const MeshFile m = loads(d.write("big.obj", text));
  ASSERT_EQ(m.mesh.triangles.size(), 1u + (n - 2) + 2u);
  EXPECT_EQ(m.mesh.materials.front(), 0u);
  EXPECT_EQ(m.mesh.materials[1], 1u);
  EXPECT_EQ(m.mesh.materials[n - 2], 1u);
  EXPECT_EQ(m.mesh.materials.back(), 0u);
  // A comb of 40,000 corners, half of them reflex: refused, naming the face, in bounded time.
  text = "";
  for (int i = 0; i < 20000; ++i) {
    text += 'v';
    add(2 * i);
    text += " 0 0\nv";
    add(2 * i + 1);
    text += " 10 0\n";
  }

  text += "v 40000 -5 0\nv 0 -5 0\nf";
  for (int i = 1; i <= 40002; ++i) add(i);
  text += "\n";
  const std::string msg = refusal(d.write("comb.obj", text));
  EXPECT_NE(msg.find("face 1, of 40002 corners, not convex: triangulating the file's faces takes "
                     "more than"),
            std::string::npos)
      << msg;
}

TEST(MeshFileObj, NormalsAndUvsSplitVertices) {
  Dir d;
  // Two triangles share positions 1 and 3 but not their normals; the second lacks a normal on
  // one corner, which gets its triangle's own normal.
  const std::string obj = d.write("n.obj",
                                  "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 2\nvn 0 1 0\n"
                                  "vt 0.25 0.75\nf 1/1/1 2/1/1 3/1/1\nf 2/1/2 4/1/2 3/1\n");
  const MeshFile m = loads(obj);
  ASSERT_EQ(m.mesh.triangles.size(), 2u);
  ASSERT_EQ(m.mesh.positions.size(), 6u);
  ASSERT_EQ(m.mesh.normals.size(), 6u);
  ASSERT_EQ(m.mesh.uvs.size(), 6u);
  EXPECT_FLOAT_EQ(m.mesh.normals[0].z, 1);  // (0, 0, 2) normalised
  EXPECT_FLOAT_EQ(m.mesh.normals[3].y, 1);
  // Corner 3 of triangle 2 has no normal: the flat normal of (1,0,0), (1,1,0), (0,1,0) is +z.
  const std::uint32_t c = m.mesh.triangles[1][2];
  EXPECT_FLOAT_EQ(m.mesh.normals[c].z, 1);
  EXPECT_FLOAT_EQ(m.mesh.uvs[0][0], 0.25f);
  EXPECT_FLOAT_EQ(m.mesh.uvs[0][1], 0.25f);  // 1 - v: the texture convention's v runs down
}

TEST(MeshFileObj, RefusesMissingMtl) {
  Dir d;
  const std::string obj = d.write("q.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string msg = refusal(obj);
  EXPECT_EQ(msg.rfind(prefix("q.obj"), 0), 0u) << msg;
  EXPECT_NE(msg.find("gone.mtl"), std::string::npos) << msg;
  EXPECT_NE(msg.find("not found"), std::string::npos) << msg;
}

TEST(MeshFileObj, RefusesKdOutsideTheUnitRangeAndNegativeKe) {
  Dir d;
  d.write("m.mtl", "newmtl hot\nKd 1.5 0 0\n");
  d.write("k.mtl", "newmtl dark\nKd 0.5 0.5 0.5\nKe 0 -1 0\n");
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::string msg = refusal(d.write("a.obj", "mtllib m.mtl\nusemtl hot\n" + tri));
  EXPECT_EQ(msg, prefix("a.obj") + "material 'hot' in m.mtl: Kd 1.5 is outside [0, 1]");
  msg = refusal(d.write("b.obj", "mtllib k.mtl\nusemtl dark\n" + tri));
  EXPECT_EQ(msg, prefix("b.obj") + "material 'dark' in k.mtl: Ke -1 must be a finite number >= 0");
}

TEST(MeshFileObj, RefusesIndicesOutOfRange) {
  Dir d;
  std::string msg = refusal(d.write("i.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"));
  EXPECT_EQ(msg, prefix("i.obj") + "i.obj line 4: vertex index 9 out of range (3 in the file)");
  // A quad, which tinyobjloader would drop silently.
  msg = refusal(d.write("q.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 7\n"));
  EXPECT_NE(msg.find("vertex index 7 out of range"), std::string::npos) << msg;
  msg = refusal(d.write("n.obj", "v 0 0 0\nv 1 0 0\nf 1 2 -3\nv 0 1 0\n"));
  EXPECT_EQ(msg, prefix("n.obj") + "n.obj line 3: vertex index -3 out of range (2 before it)");
  msg = refusal(d.write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n"));
  EXPECT_NE(msg.find("line 5: normal index 2 out of range (1 in the file)"), std::string::npos)
      << msg;
  msg = refusal(d.write("z.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"));
  EXPECT_NE(msg.find("line 4: '0' is not a valid vertex index"), std::string::npos) << msg;
}

TEST(MeshFileObj, RefusesNonFiniteCoordinates) {
  Dir d;
  std::string msg = refusal(d.write("n.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_EQ(msg, prefix("n.obj") + "n.obj line 2: 'nan' is not a finite number");
  msg = refusal(d.write("i.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_NE(msg.find("line 2: '1e999' is not a finite number"), std::string::npos) << msg;
  msg = refusal(d.write("s.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_NE(msg.find("line 2: 'v' needs 3 numbers"), std::string::npos) << msg;
  // Finite as written, infinite as a float: named by its line (it was "centre [inf, -nan, -nan]").
  msg = refusal(d.write("f.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_EQ(msg, prefix("f.obj") + "f.obj line 2: '1e39' is past the float range (3.4e+38)");
}

TEST(MeshFile, RefusesMissingAndUnknownFiles) {
  Dir d;
  std::string msg = refusal(d.file("nothing.obj"));
  EXPECT_EQ(msg.rfind(prefix("nothing.obj") + "the file not found", 0), 0u) << msg;
  msg = refusal(d.file("nothing.glb"));
  EXPECT_NE(msg.find("not found"), std::string::npos) << msg;
  msg = refusal(d.write("x.ply", "ply\n"));
  EXPECT_EQ(msg, prefix("x.ply") + "unknown mesh file type '.ply' (expected .obj, .gltf or .glb)");
  fs::create_directory(d.file("dir.obj"));
  msg = refusal(d.file("dir.obj"));
  EXPECT_NE(msg.find("not a regular file"), std::string::npos) << msg;
}

TEST(MeshFile, RefusesPastTheMemoryLimit) {
  if (!have(kBunny)) return;
  // The file itself, before it is read.
  std::string msg = refusal(kBunny, 1000);
  EXPECT_NE(msg.find("the file has " + std::to_string(fs::file_size(kBunny)) +
                     " bytes, more than the memory limit of 1000 bytes"),
            std::string::npos)
      << msg;
  // The arrays, before they are allocated: the file fits, its triangles do not.
  msg = refusal(kBunny, fs::file_size(kBunny) + 1000);
  EXPECT_NE(msg.find("69666 triangles need"), std::string::npos) << msg;
  EXPECT_NE(msg.find("more than the memory limit"), std::string::npos) << msg;
  if (!have(kGltf2 + "2CylinderEngine-glTF-Binary/2CylinderEngine.glb")) return;
  const std::string engine = kGltf2 + "2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
  // Its bytes and their copy in tinygltf's buffers fit, the arrays do not.
  msg = refusal(engine, 3 * fs::file_size(engine));
  EXPECT_NE(msg.find("121496 triangles on 84657 vertices need 8335364 bytes (7.9 MiB) in all"),
            std::string::npos)
      << msg;
  // Parsing is counted before it starts: a JSON chunk of 43 KB (its objects cost most).
  msg = refusal(engine, fs::file_size(engine) + 1000);
  EXPECT_NE(msg.find("parsing its JSON (43444 bytes) need"), std::string::npos) << msg;
}

// ---- glTF, hand-written ----

std::string base64(const std::string& bytes) {
  static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    std::uint32_t n = std::uint32_t(std::uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size()) n |= std::uint32_t(std::uint8_t(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) n |= std::uint8_t(bytes[i + 2]);
    const std::size_t rest = bytes.size() - i;
    out += digits[(n >> 18) & 63];
    out += digits[(n >> 12) & 63];
    out += rest > 1 ? digits[(n >> 6) & 63] : '=';
    out += rest > 2 ? digits[n & 63] : '=';
  }
  return out;
}

template <typename T>
std::string bytes_of(const std::vector<T>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

// A glTF document whose buffer 0 holds positions (accessor 0: the first `vertices` floats
// triples) followed by `indices` as uint16 (accessor 1 when any), as a data URI.
json gltf(const std::vector<float>& positions, const std::vector<std::uint16_t>& indices = {}) {
  std::string data = bytes_of(positions);
  const std::size_t pos_bytes = data.size();
  data += bytes_of(indices);
  json j = {{"asset", {{"version", "2.0"}}},
            {"buffers",
             {{{"byteLength", data.size()},
               {"uri", "data:application/octet-stream;base64," + base64(data)}}}},
            {"bufferViews", {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", pos_bytes}}}},
            {"accessors",
             {{{"bufferView", 0},
               {"componentType", 5126},
               {"count", positions.size() / 3},
               {"type", "VEC3"}}}},
            {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}}}}}}},
            {"nodes", {{{"mesh", 0}}}},
            {"scenes", {{{"nodes", {0}}}}},
            {"scene", 0}};
  if (!indices.empty()) {
    j["bufferViews"].push_back(
        {{"buffer", 0}, {"byteOffset", pos_bytes}, {"byteLength", indices.size() * 2}});
    j["accessors"].push_back({{"bufferView", 1},
                              {"componentType", 5123},
                              {"count", indices.size()},
                              {"type", "SCALAR"}});
    j["meshes"][0]["primitives"][0]["indices"] = 1;
  }
  return j;
}

const std::vector<float> kTriangle = {0, 0, 0, 1, 0, 0, 0, 1, 0};

TEST(MeshFileGltf, Base64OfTheTestIsRight) {
  EXPECT_EQ(base64("Man"), "TWFu");
  EXPECT_EQ(base64("Ma"), "TWE=");
  EXPECT_EQ(base64("M"), "TQ==");
}

TEST(MeshFileGltf, ComposesTrsDownTheTree) {
  Dir d;
  json j = gltf(kTriangle);
  const double h = std::sqrt(0.5);
  // Parent translates; child scales by 2, then turns 90 degrees about z.
  j["nodes"] = {{{"children", {1}}, {"translation", {1, 2, 3}}},
                {{"mesh", 0}, {"rotation", {0, 0, h, h}}, {"scale", {2, 2, 2}}}};
  const MeshFile m = loads(d.write("t.gltf", j.dump()));
  ASSERT_EQ(m.mesh.positions.size(), 3u);
  ASSERT_EQ(m.mesh.triangles.size(), 1u);
  // (1, 0, 0) -> scale (2, 0, 0) -> rotate (0, 2, 0) -> translate (1, 4, 3).
  EXPECT_NEAR(m.mesh.positions[1].x, 1, 1e-6);
  EXPECT_NEAR(m.mesh.positions[1].y, 4, 1e-6);
  EXPECT_NEAR(m.mesh.positions[1].z, 3, 1e-6);
  // (0, 1, 0) -> (0, 2, 0) -> (-2, 0, 0) -> (-1, 2, 3).
  EXPECT_NEAR(m.mesh.positions[2].x, -1, 1e-6);
  EXPECT_NEAR(m.mesh.positions[2].y, 2, 1e-6);
  // No primitive has normals: flat shading.
  EXPECT_TRUE(m.mesh.normals.empty());
  // No material: the glTF spec's default, baseColorFactor 1.
  ASSERT_EQ(m.materials.size(), 1u);
  EXPECT_FLOAT_EQ(m.materials[0].albedo.r, 1);
  EXPECT_FLOAT_EQ(m.materials[0].emission.r, 0);
}

TEST(MeshFileGltf, MatrixIsColumnMajorAndMeshesAreInstancedPerNode) {
  Dir d;
  json j = gltf(kTriangle);
  // Scale 3, then translate by (5, 6, 7): column-major, translation in elements 12..14.
  j["nodes"] = {{{"mesh", 0}, {"matrix", {3, 0, 0, 0, 0, 3, 0, 0, 0, 0, 3, 0, 5, 6, 7, 1}}},
                {{"mesh", 0}}};
  j["scenes"][0]["nodes"] = {0, 1};
  const MeshFile m = loads(d.write("m.gltf", j.dump()));
  ASSERT_EQ(m.mesh.triangles.size(), 2u);
  ASSERT_EQ(m.mesh.positions.size(), 6u);
  std::vector<float> xs;
  for (const Vec3& p : m.mesh.positions) xs.push_back(p.x);
  std::sort(xs.begin(), xs.end());
  EXPECT_EQ(xs, (std::vector<float>{0, 0, 1, 5, 5, 8}));
  const auto it = std::find_if(m.mesh.positions.begin(), m.mesh.positions.end(),
                               [](Vec3 p) { return p.x == 8; });
  ASSERT_NE(it, m.mesh.positions.end());
  EXPECT_FLOAT_EQ(it->y, 6);
  EXPECT_FLOAT_EQ(it->z, 7);
}

TEST(MeshFileGltf, StripsAndFansBecomeTriangles) {
  Dir d;
  const std::vector<float> quad = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0};
  for (int mode : {5, 6}) {
    json j = gltf(quad);
    j["meshes"][0]["primitives"][0]["mode"] = mode;
    const MeshFile m = loads(d.write("s.gltf", j.dump()));
    ASSERT_EQ(m.mesh.triangles.size(), 3u) << mode;
    using T = std::array<std::uint32_t, 3>;
    if (mode == 5) {
      EXPECT_EQ(m.mesh.triangles[1], (T{2, 1, 3}));  // odd strip triangles keep the winding
      EXPECT_EQ(m.mesh.triangles[2], (T{2, 3, 4}));
    } else {
      EXPECT_EQ(m.mesh.triangles[2], (T{0, 3, 4}));
    }
  }
  json j = gltf(quad, {0, 1, 2, 2, 1, 3});
  const MeshFile m = loads(d.write("i.gltf", j.dump()));
  ASSERT_EQ(m.mesh.triangles.size(), 2u);
  EXPECT_EQ(m.mesh.triangles[1], (std::array<std::uint32_t, 3>{2, 1, 3}));
}

TEST(MeshFileGltf, RefusesLinesAndPoints) {
  Dir d;
  json j = gltf(kTriangle);
  j["meshes"][0]["primitives"].push_back(j["meshes"][0]["primitives"][0]);
  j["meshes"][0]["primitives"][1]["mode"] = 1;
  EXPECT_EQ(
      refusal(d.write("l.gltf", j.dump())),
      prefix("l.gltf") + "meshes[0].primitives[1]: mode LINES is not supported (triangles only)");
  j["meshes"][0]["primitives"][1]["mode"] = 0;
  EXPECT_NE(refusal(d.write("p.gltf", j.dump())).find("mode POINTS is not supported"),
            std::string::npos);
}

TEST(MeshFileGltf, RefusesIndicesOutOfRangeAndBadAccessors) {
  Dir d;
  EXPECT_EQ(refusal(d.write("i.gltf", gltf(kTriangle, {0, 1, 5}).dump())),
            prefix("i.gltf") + "accessors[1]: index 5 out of range (3 vertices)");
  json j = gltf(kTriangle);
  j["accessors"][0]["count"] = 4;
  std::string msg = refusal(d.write("c.gltf", j.dump()));
  EXPECT_NE(msg.find("accessors[0] (POSITION of meshes[0].primitives[0]): byteOffset 0 + 4 "
                     "elements of stride 12 pass the end of bufferViews[0] (36 bytes)"),
            std::string::npos)
      << msg;
  j = gltf(kTriangle);
  j["accessors"][0]["type"] = "VEC2";
  msg = refusal(d.write("t.gltf", j.dump()));
  EXPECT_NE(msg.find("expected type VEC3, found VEC2"), std::string::npos) << msg;
  j = gltf(kTriangle);
  j["bufferViews"][0]["byteLength"] = 400;
  msg = refusal(d.write("b.gltf", j.dump()));
  EXPECT_NE(msg.find("bufferViews[0]"), std::string::npos) << msg;
  j = gltf(kTriangle);
  j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 9;
  msg = refusal(d.write("a.gltf", j.dump()));
  EXPECT_NE(msg.find("meshes[0].primitives[0]: POSITION accessor 9 does not exist (1 accessors)"),
            std::string::npos)
      << msg;
  j = gltf({0, 0, 0, 1, 0, 0, 0, std::nanf(""), 0});
  msg = refusal(d.write("n.gltf", j.dump()));
  EXPECT_NE(msg.find("accessors[0]: position 2 (0, nan, 0) is not finite"), std::string::npos)
      << msg;
}

TEST(MeshFileGltf, RefusesSparseAccessorsAndMissingImages) {
  Dir d;
  json j = gltf(kTriangle);
  j["accessors"][0]["sparse"] = {{"count", 1},
                                 {"indices", {{"bufferView", 0}, {"componentType", 5125}}},
                                 {"values", {{"bufferView", 0}}}};
  EXPECT_EQ(refusal(d.write("s.gltf", j.dump())),
            prefix("s.gltf") +
                "accessors[0] (POSITION of meshes[0].primitives[0]): sparse "
                "accessors are not supported");
  // A textured material whose image file is not there.
  j = gltf({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1});
  j["accessors"][0]["count"] = 3;
  j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 24}});
  j["accessors"].push_back(
      {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}});
  j["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 1;
  j["meshes"][0]["primitives"][0]["material"] = 0;
  j["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
  j["textures"] = {{{"source", 0}}};
  j["images"] = {{{"uri", "missing.png"}}};
  const std::string msg = refusal(d.write("t.gltf", j.dump()));
  EXPECT_EQ(msg, prefix("t.gltf") + "images[0]: no image data ('missing.png' could not be read)");
  // An image in a buffer view that runs past its buffer (tinygltf does not check this one; the
  // fuzzer found it reading past the buffer).
  j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 40}, {"byteLength", 10000}});
  j["images"] = {{{"bufferView", 2}, {"mimeType", "image/png"}}};
  EXPECT_EQ(refusal(d.write("v.gltf", j.dump())),
            prefix("v.gltf") +
                "bufferViews[2]: byteOffset 40 + byteLength 10000 passes the end of buffers[0] "
                "(60 bytes)");
}

TEST(MeshFileGltf, MaterialsAndMixedNormals) {
  Dir d;
  // Two primitives on the same positions: the first with normals (all -z... scaled), the second
  // without, which gets flat normals on vertices of its own.
  std::vector<float> data = kTriangle;
  for (int k = 0; k < 3; ++k) data.insert(data.end(), {0, 0, -3});
  json j = gltf(data);
  j["accessors"][0]["count"] = 3;
  j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 36}});
  j["accessors"].push_back(
      {{"bufferView", 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}});
  j["meshes"][0]["primitives"] = {
      {{"attributes", {{"POSITION", 0}, {"NORMAL", 1}}}, {"material", 0}},
      {{"attributes", {{"POSITION", 0}}}}};
  j["materials"] = {
      {{"name", "glow"},
       {"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.25, 1, 0.1}}}},
       {"emissiveFactor", {1, 0.5, 0}},
       {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4}}}}}}};
  const MeshFile m = loads(d.write("n.gltf", j.dump()));
  ASSERT_EQ(m.mesh.positions.size(), 6u);
  ASSERT_EQ(m.mesh.normals.size(), 6u);
  EXPECT_FLOAT_EQ(m.mesh.normals[0].z, -1);
  EXPECT_FLOAT_EQ(m.mesh.normals[4].z, 1);  // flat: counter-clockwise seen from +z
  ASSERT_EQ(m.materials.size(), 2u);
  EXPECT_EQ(m.materials[0].name, "glow");
  EXPECT_FLOAT_EQ(m.materials[0].albedo.g, 0.25f);
  EXPECT_FLOAT_EQ(m.materials[0].emission.r, 4);
  EXPECT_FLOAT_EQ(m.materials[0].emission.g, 2);
  EXPECT_FLOAT_EQ(m.materials[1].albedo.g, 1);  // the spec's default material: a rough metal
  EXPECT_EQ(m.materials[1].metallic, 1);
  EXPECT_EQ(m.materials[1].roughness, 1);
  EXPECT_EQ(m.materials[0].metallic, 1);  // factors absent: glTF's 1
  EXPECT_FALSE(m.materials[0].lambertian());
  EXPECT_EQ(m.mesh.materials, (std::vector<std::uint32_t>{0, 1}));

  j["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = {1.5, 0, 0, 1};
  EXPECT_EQ(refusal(d.write("c.gltf", j.dump())),
            prefix("c.gltf") +
                "materials[0].pbrMetallicRoughness.baseColorFactor: 1.5 is outside [0, 1]");
}

TEST(MeshFileGltf, MetallicRoughnessTexturesAndTheirTransforms) {
  Dir d;
  two_texels(d, "t.png");
  // A triangle with TEXCOORD_0 and TEXCOORD_1.
  std::vector<float> data = kTriangle;
  for (float v : {0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 0.5f, 0.5f, 1.f, 1.f, 0.f, 1.f}) data.push_back(v);
  json j = gltf(data);
  j["accessors"][0]["count"] = 3;
  j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 24}});
  j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 60}, {"byteLength", 24}});
  for (int v : {1, 2})
    j["accessors"].push_back(
        {{"bufferView", v}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}});
  j["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 1;
  j["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = 2;
  j["meshes"][0]["primitives"][0]["material"] = 0;
  j["extensionsUsed"] = {"KHR_texture_transform", "KHR_materials_clearcoat"};
  j["materials"] = {{{"pbrMetallicRoughness",
                      {{"metallicFactor", 0.25},
                       {"roughnessFactor", 0.5},
                       {"baseColorTexture",
                        {{"index", 0},
                         {"extensions",
                          {{"KHR_texture_transform",
                            {{"offset", {0.5, 0}}, {"rotation", 0}, {"scale", {2, 1}}}}}}}},
                       {"metallicRoughnessTexture", {{"index", 0}, {"texCoord", 1}}}}},
                     {"emissiveTexture", {{"index", 0}}},
                     {"emissiveFactor", {1, 1, 1}}}};
  j["textures"] = {{{"source", 0}}};
  j["images"] = {{{"uri", "t.png"}}};
  const MeshFile m = loads(d.write("g.gltf", j.dump()));
  ASSERT_EQ(m.materials.size(), 1u);
  const Material& mat = m.materials[0];
  EXPECT_EQ(mat.metallic, 0.25f);
  EXPECT_EQ(mat.roughness, 0.5f);
  EXPECT_FALSE(mat.lambertian());
  // One image, decoded twice: sRGB for colours, as stored for metallic and roughness.
  ASSERT_EQ(m.textures.size(), 2u);
  EXPECT_EQ(mat.albedo_texture.index, mat.emission_texture.index);
  const Texture& linear = m.textures[std::size_t(mat.metallic_roughness_texture.index)];
  const Texture& srgb = m.textures[std::size_t(mat.albedo_texture.index)];
  EXPECT_NEAR(linear.rgb[1], 128 / 255.0, 1e-6);
  EXPECT_NEAR(srgb.rgb[1], srgb_to_linear(128), 1e-6);
  EXPECT_EQ(mat.metallic_roughness_texture.uv_set, 1);
  EXPECT_EQ(mat.albedo_texture.uv_set, 0);
  EXPECT_EQ(mat.albedo_texture.transform, (std::array<float, 6>{2, 0, 0.5f, -0.f, 1, 0}));
  ASSERT_EQ(m.mesh.uvs.size(), 3u);
  ASSERT_EQ(m.mesh.lightmap_uvs.size(), 3u);
  EXPECT_EQ(m.mesh.lightmap_uvs[0][0], 0.5f);
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_EQ(m.warnings[0],
            "uses KHR_materials_clearcoat, which is not implemented: drawn without it");

  // A rotation turns (u, v) by the extension's matrix: (cos, sin; -sin, cos).
  auto& tt = j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]
              ["KHR_texture_transform"];
  tt = {{"rotation", std::numbers::pi / 2}, {"texCoord", 1}};
  const MeshFile r = loads(d.write("r.gltf", j.dump()));
  const auto& rt = r.materials[0].albedo_texture;
  EXPECT_EQ(rt.uv_set, 1);
  EXPECT_NEAR(rt.transform[0], 0, 1e-7);
  EXPECT_NEAR(rt.transform[1], 1, 1e-7);
  EXPECT_NEAR(rt.transform[3], -1, 1e-7);

  tt = {{"texCoord", 2}};
  EXPECT_EQ(refusal(d.write("c.gltf", j.dump())),
            prefix("c.gltf") +
                "materials[0].pbrMetallicRoughness.baseColorTexture: samples TEXCOORD_2; only "
                "TEXCOORD_0 and TEXCOORD_1 are supported");
  tt = {{"scale", {1, "x"}}};
  EXPECT_EQ(refusal(d.write("s.gltf", j.dump())),
            prefix("s.gltf") +
                "materials[0].pbrMetallicRoughness.baseColorTexture.extensions."
                "KHR_texture_transform.scale[1]: expected a finite number");
  tt = json::object();
  j["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = 1.5;
  EXPECT_EQ(refusal(d.write("m.gltf", j.dump())),
            prefix("m.gltf") +
                "materials[0].pbrMetallicRoughness.metallicFactor: 1.5 is outside "
                "[0, 1]");
  j["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = 0;
  j["meshes"][0]["primitives"][0]["attributes"].erase("TEXCOORD_1");
  const std::string msg = refusal(d.write("t.gltf", j.dump()));
  EXPECT_NE(msg.find("metallicRoughnessTexture samples TEXCOORD_1, which the primitive does not "
                     "have"),
            std::string::npos)
      << msg;
}

TEST(MeshFileGltf, RefusesRequiredExtensionsAndVersionOne) {
  Dir d;
  json j = gltf(kTriangle);
  j["extensionsUsed"] = {"KHR_materials_clearcoat"};
  j["extensionsRequired"] = {"KHR_materials_clearcoat"};
  EXPECT_EQ(refusal(d.write("e.gltf", j.dump())),
            prefix("e.gltf") + "extensionsRequired: KHR_materials_clearcoat is not supported");
  // Compressed data is refused even when the extension is only used: the plain data is missing.
  j = gltf(kTriangle);
  j["extensionsUsed"] = {"KHR_draco_mesh_compression"};
  j["meshes"][0]["primitives"][0]["extensions"] = {
      {"KHR_draco_mesh_compression", {{"bufferView", 0}, {"attributes", {{"POSITION", 0}}}}}};
  EXPECT_EQ(refusal(d.write("d.gltf", j.dump())),
            prefix("d.gltf") +
                "meshes[0].primitives[0]: Draco compression "
                "(KHR_draco_mesh_compression) is not supported");
  j = gltf(kTriangle);
  j["extensionsUsed"] = {"EXT_meshopt_compression"};
  j["bufferViews"][0]["extensions"] = {{"EXT_meshopt_compression",
                                        {{"buffer", 0},
                                         {"byteLength", 36},
                                         {"byteStride", 12},
                                         {"count", 3},
                                         {"mode", "ATTRIBUTES"}}}};
  EXPECT_EQ(refusal(d.write("o.gltf", j.dump())),
            prefix("o.gltf") +
                "bufferViews[0]: meshopt compression (EXT_meshopt_compression) is "
                "not supported");
  j = gltf(kTriangle);
  j["asset"]["version"] = "1.0";
  EXPECT_EQ(refusal(d.write("v.gltf", j.dump())),
            prefix("v.gltf") + "glTF 2.0 is needed (this file is version 1.0)");
}

TEST(MeshFileGltf, RefusesCyclesAndKeepsDeepTrees) {
  Dir d;
  json j = gltf(kTriangle);
  j["nodes"] = {{{"children", {1}}}, {{"children", {2}}}, {{"children", {1}}, {"mesh", 0}}};
  std::string msg = refusal(d.write("c.gltf", j.dump()));
  EXPECT_NE(msg.find("two parents or in a cycle"), std::string::npos) << msg;
  // 20000 nested nodes, each translating by 1: no recursion, so no stack overflow.
  j = gltf(kTriangle);
  const int depth = 20000;
  j["nodes"] = json::array();
  for (int i = 0; i < depth; ++i) {
    json node = {{"translation", {1, 0, 0}}};
    if (i + 1 < depth) node["children"] = {i + 1};
    if (i + 1 == depth) node["mesh"] = 0;
    j["nodes"].push_back(node);
  }
  const MeshFile m = loads(d.write("deep.gltf", j.dump()));
  ASSERT_EQ(m.mesh.positions.size(), 3u);
  EXPECT_FLOAT_EQ(m.mesh.positions[0].x, float(depth));
  // `extras` nested 30,000 deep (60 KB): tinygltf reads them by recursion and overflowed the
  // stack; refused before it, naming where. 500 levels load.
  for (const int levels : {500, 30000}) {
    std::string text = gltf(kTriangle).dump();
    text.pop_back();  // the closing brace
    text += ",\"extras\":" + std::string(std::size_t(levels), '[') +
            std::string(std::size_t(levels), ']') + "}";
    const std::string file = d.write("nested" + std::to_string(levels) + ".gltf", text);
    if (levels == 500) {
      EXPECT_EQ(loads(file).mesh.positions.size(), 3u);
      continue;
    }
    msg = refusal(file);
    EXPECT_NE(msg.find("extras[0][0][0]"), std::string::npos) << msg;
    EXPECT_NE(msg.find("nests more than 512 levels deep"), std::string::npos) << msg;
  }
}

// ---- glTF, the assimp test models ----

TEST(MeshFileAssimp, BoxTexturedInEveryForm) {
  for (const char* f :
       {"BoxTextured-glTF/BoxTextured.gltf", "BoxTextured-glTF-Binary/BoxTextured.glb",
        "BoxTextured-glTF-Embedded/BoxTextured.gltf"}) {
    if (!have(kGltf2 + f)) continue;
    const MeshFile m = loads(kGltf2 + f);
    EXPECT_EQ(m.mesh.triangles.size(), 12u) << f;
    EXPECT_EQ(m.mesh.positions.size(), 24u) << f;
    EXPECT_EQ(m.mesh.normals.size(), 24u) << f;
    EXPECT_EQ(m.mesh.uvs.size(), 24u) << f;
    ASSERT_EQ(m.textures.size(), 1u) << f;
    EXPECT_EQ(m.textures[0].width, 211) << f;
    EXPECT_EQ(m.textures[0].height, 211) << f;
    // The .gltf's sampler: wrapS MIRRORED_REPEAT, wrapT CLAMP_TO_EDGE; the others' REPEAT.
    const bool gltf = std::string(f).starts_with("BoxTextured-glTF/");
    EXPECT_EQ(m.textures[0].wrap_s, gltf ? Texture::Wrap::mirror : Texture::Wrap::repeat) << f;
    EXPECT_EQ(m.textures[0].wrap_t, gltf ? Texture::Wrap::clamp : Texture::Wrap::repeat) << f;
    EXPECT_FALSE(m.textures[0].nearest) << f;
    ASSERT_EQ(m.materials.size(), 1u) << f;
    EXPECT_EQ(m.materials[0].albedo_texture.index, 0) << f;
  }
}

TEST(MeshFileAssimp, BoxTexturedTextureIsTheDecodedPng) {
  const std::string dir = kGltf2 + "BoxTextured-glTF/";
  if (!have(dir + "BoxTextured.gltf")) return;
  const MeshFile m = loads(dir + "BoxTextured.gltf");
  ASSERT_EQ(m.textures.size(), 1u);
  int w = 0, h = 0, n = 0;
  unsigned char* png = stbi_load((dir + "CesiumLogoFlat.png").c_str(), &w, &h, &n, 3);
  ASSERT_NE(png, nullptr);
  ASSERT_EQ(w, 211);
  int checked = 0;
  for (const auto& [x, y] : {std::pair{0, 0}, std::pair{105, 40}, std::pair{30, 170},
                             std::pair{210, 210}, std::pair{150, 100}}) {
    // A texel centre: bilinear filtering returns the texel itself.
    const Rgb got = sample_texture(m.textures[0], (x + 0.5f) / float(w), (y + 0.5f) / float(h));
    const unsigned char* p = png + (std::size_t(y) * std::size_t(w) + std::size_t(x)) * 3;
    EXPECT_NEAR(got.r, srgb_to_linear(p[0]), 1e-6) << x << "," << y;
    EXPECT_NEAR(got.g, srgb_to_linear(p[1]), 1e-6) << x << "," << y;
    EXPECT_NEAR(got.b, srgb_to_linear(p[2]), 1e-6) << x << "," << y;
    ++checked;
  }
  // The picked texels are not all alike (the test would not see a wrong row order otherwise).
  EXPECT_NE(png[0], png[(100 * 211 + 150) * 3 + 1]);
  stbi_image_free(png);
  EXPECT_EQ(checked, 5);
}

TEST(MeshFileAssimp, TextureTransformsClearcoatAndSecondSets) {
  // KHR_texture_transform's test model: each material's map as the extension composes it.
  const std::string tt = kGltf2 + "textureTransform/TextureTransformTest.gltf";
  if (!have(tt)) return;
  const MeshFile t = loads(tt);
  ASSERT_GE(t.materials.size(), 6u);
  EXPECT_TRUE(t.warnings.empty());
  auto transform = [&](const std::string& name) {
    for (const Material& m : t.materials)
      if (m.name == name) return m.albedo_texture.transform;
    ADD_FAILURE() << "no material " << name;
    return std::array<float, 6>{};
  };
  EXPECT_EQ(transform("Offset U"), (std::array<float, 6>{1, 0, 0.5f, -0.f, 1, 0}));
  EXPECT_EQ(transform("Offset V"), (std::array<float, 6>{1, 0, 0, -0.f, 1, 0.5f}));
  const double a = 0.3, c = std::cos(a), s = std::sin(a);
  const auto all = transform("All");
  const double want[6] = {c * 1.5, s * 1.5, -0.2, -s * 1.5, c * 1.5, -0.1};
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(all[std::size_t(k)], want[k], 1e-6) << k;
  EXPECT_EQ(transform("Correct"), (std::array<float, 6>{1, 0, 0, 0, 1, 0}));

  // ClearCoatTest: glossy dielectrics, a roughness texture (linear), emissive labels, and the
  // clearcoat it uses named in a warning.
  const std::string cc = kGltf2 + "ClearCoat-glTF/ClearCoatTest.gltf";
  if (!have(cc)) return;
  const MeshFile m = loads(cc);
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_EQ(m.warnings[0],
            "uses KHR_materials_clearcoat, which is not implemented: drawn without it");
  int labels = 0, rough = 0, glossy = 0;
  for (const Material& mat : m.materials) {
    labels += mat.emission_texture.index >= 0;
    rough += mat.metallic_roughness_texture.index >= 0;
    glossy += mat.metallic == 0 && mat.roughness < 1;
  }
  EXPECT_EQ(labels, 1);
  EXPECT_EQ(rough, 1);
  EXPECT_GE(glossy, 15);

  // boxTexcoords: its metallic-roughness texture samples TEXCOORD_1, its colour TEXCOORD_0.
  const std::string bt = kGltf2 + "BoxTexcoords-glTF/boxTexcoords.gltf";
  if (!have(bt)) return;
  const MeshFile b = loads(bt);
  ASSERT_EQ(b.materials.size(), 1u);
  EXPECT_EQ(b.materials[0].albedo_texture.uv_set, 0);
  EXPECT_EQ(b.materials[0].metallic_roughness_texture.uv_set, 1);
  EXPECT_EQ(b.mesh.uvs.size(), b.mesh.positions.size());
  EXPECT_EQ(b.mesh.lightmap_uvs.size(), b.mesh.positions.size());
}

TEST(MeshFileAssimp, ValidModelsHaveTheirTriangleCounts) {
  // Counts from the files' index accessors (count / 3 per primitive instance).
  const std::pair<const char*, std::size_t> models[] = {
      {"BoxTexcoords-glTF/boxTexcoords.gltf", 12},
      {"2CylinderEngine-glTF-Binary/2CylinderEngine.glb", 121496},
      {"TestNoRootNode/SceneWithoutNodes.gltf", 0},  // a valid scene with no nodes: empty
  };
  for (const auto& [file, triangles] : models) {
    if (!have(kGltf2 + file)) continue;
    const MeshFile m = loads(kGltf2 + file);
    EXPECT_EQ(m.mesh.triangles.size(), triangles) << file;
    for (const Vec3& p : m.mesh.positions)
      ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << file;
    for (const auto& t : m.mesh.triangles)
      for (std::uint32_t v : t) ASSERT_LT(v, m.mesh.positions.size()) << file;
  }
}

TEST(MeshFileAssimp, MalformedFilesAreRefused) {
  // File, then what the message must say.
  const std::pair<const char*, const char*> cases[] = {
      {"wrongTypes/badArray.gltf", "meshes[0].primitives: expected an array, found an object"},
      {"wrongTypes/badExtension.gltf",
       "baseColorTexture.extensions.KHR_texture_transform: expected an object, found the string"},
      {"wrongTypes/badNumber.gltf", "materials[0].normalTexture.scale: expected a number"},
      {"wrongTypes/badObject.gltf",
       "materials[0].pbrMetallicRoughness: expected an object, found an array"},
      {"wrongTypes/badString.gltf", "scenes[0].name: expected a string, found 42"},
      {"wrongTypes/badUint.gltf", "baseColorTexture.index: expected an integer >= 0, found -1"},
      {"RecursiveNodes/RecursiveNodes.gltf", "nodes[0]: the node hierarchy has a cycle"},
      {"BoxTextured-glTF-techniqueWebGL/BoxTextured.gltf",
       "extensionsRequired: KHR_technique_webgl is not supported"},
      {"TestNoRootNode/NoScene.gltf", "scene: scene 0 does not exist (the file has no scenes)"},
      {"issue_3269/texcoord_crash.gltf",
       "baseColorTexture samples TEXCOORD_0, which the primitive does not have"},
      {"IndexOutOfRange/IndexOutOfRange.gltf",
       "accessors[0]: index 255 out of range (24 vertices)"},
      {"IndexOutOfRange/AllIndicesOutOfRange.gltf",
       "accessors[0]: index 65535 out of range (24 vertices)"},
      {"IncorrectVertexArrays/Cube.gltf",
       "meshes[1].primitives[0]: mode TRIANGLES with 35 vertices (not a multiple of 3)"},
      {"MissingBin/BoxTextured.gltf", "File not found : BoxTextured0.bin"},
      {"BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
       "accessors[2]: position 0 (-inf, -0.5, 0.5) is not finite"},
      {"BoxBadNormals-glTF-Binary/BoxBadNormals.glb",
       "accessors[1]: normal 0 (0, 0, 0) is not a finite non-zero vector"},
      {"SchemaFailures/sceneWrongType.gltf",
       "scene: expected an integer >= 0, found the string \"hello\""},
      {"draco/2CylinderEngine.gltf",
       "extensionsRequired: KHR_draco_mesh_compression is not supported"},
  };
  for (const auto& [file, what] : cases) {
    if (!have(kGltf2 + file)) continue;
    const std::string msg = refusal(kGltf2 + file);
    const std::string name = fs::path(file).filename().string();
    EXPECT_EQ(msg.rfind(prefix(name), 0), 0u) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << file << ": " << msg;
    std::cout << file << ": " << msg.substr(std::min(msg.size(), prefix(name).size())) << "\n";
  }
}

TEST(MeshFileAssimp, GltfVersionOneIsRefused) {
  if (!have(kGltf1)) return;
  int files = 0;
  for (const auto& e : fs::recursive_directory_iterator(kGltf1)) {
    const std::string ext = e.path().extension().string();
    if (ext != ".gltf" && ext != ".glb") continue;
    ++files;
    const std::string msg = refusal(e.path().string());
    EXPECT_NE(msg.find("glTF 2.0 is needed (this file is"), std::string::npos) << msg;
  }
  EXPECT_GE(files, 7);
}

// Every glTF 2.0 file of the package either loads or is refused with a message; none crashes,
// hangs or throws anything else. The outcome of each is printed (docs list the refusals).
TEST(MeshFileAssimp, EveryGltf2FileLoadsOrIsRefused) {
  if (!have(kGltf2)) return;
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(kGltf2)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".gltf" || ext == ".glb") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  EXPECT_GE(files.size(), 40u);
  int loaded = 0;
  for (const fs::path& f : files) {
    const std::string rel = f.string().substr(kGltf2.size());
    try {
      const MeshFile m = read(f.string());
      ++loaded;
      std::cout << rel << ": loads, " << m.mesh.triangles.size() << " triangles\n";
      for (const auto& t : m.mesh.triangles)
        for (std::uint32_t v : t) ASSERT_LT(v, m.mesh.positions.size()) << rel;
      EXPECT_EQ(m.mesh.materials.size(), m.mesh.triangles.size()) << rel;
      EXPECT_TRUE(m.mesh.normals.empty() || m.mesh.normals.size() == m.mesh.positions.size());
    } catch (const io::JsonFailure& e) {
      EXPECT_EQ(e.message.rfind(prefix(f.filename().string()), 0), 0u) << e.message;
      std::cout << rel << ": refused: " << e.message.substr(prefix(f.filename().string()).size())
                << "\n";
    }
  }
  EXPECT_GE(loaded, 5);
}

}  // namespace
}  // namespace penumbra::spaceland
