// The 3D scene document: parsing, defaults, transforms, every error rule, check_scene, bounds.
// Suites Scene3dMeshFile* read real OBJ / glTF files and need the mesh file reader.
#include "penumbra/spaceland/scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "spaceland/scene/transform.hpp"
#include "test_support.hpp"

namespace penumbra::spaceland {
namespace {

namespace fs = std::filesystem;

// The spec's example document without its mesh object (mesh files have tests of their own).
constexpr const char* kExample = R"({
  "penumbra": 1,
  "dimensions": 3,
  "camera": { "position": [0, 1, 3.4], "look_at": [0, 1, 0], "up": [0, 1, 0],
              "fov_y": 40, "width": 640, "height": 480 },
  "sky": { "zenith": [0.3, 0.5, 1.0], "horizon": [0.8, 0.9, 1.0], "ground": [0.2, 0.2, 0.2] },
  "sun": { "direction": [0.3, 1.0, 0.2], "irradiance": [6, 5.5, 5], "angular_radius": 0.27 },
  "materials": {
    "white": { "albedo": [0.73, 0.73, 0.73] },
    "lamp":  { "emission": [17, 12, 4] }
  },
  "objects": [
    { "type": "box", "center": [1, 0.5, 0], "size": [1, 1, 1], "rotate": [0, 15, 0], "material": "white" },
    { "type": "sphere", "center": [-1, 0.4, 0.5], "radius": 0.4, "material": { "albedo": [0.9, 0.2, 0.2] } },
    { "type": "quad", "corner": [-0.25, 1.98, -0.25], "u": [0.5, 0, 0], "v": [0, 0, 0.5], "material": "lamp" },
    { "type": "disk", "center": [0, 0, 0], "normal": [0, 1, 0], "radius": 10, "material": "white" }
  ],
  "media": [
    { "type": "box", "center": [0, 1, 0], "size": [4, 2, 4], "extinction": 0.2, "albedo": [0.8, 0.8, 0.8] }
  ]
})";

constexpr const char* kBunny = "/usr/share/glmark2/models/bunny.obj";

struct TempDir : testing::TestDir {
  TempDir() : testing::TestDir("scene3d") {}
};

// A valid document with `extra` members after the camera.
std::string doc(const std::string& extra) {
  return R"({"penumbra": 1, "dimensions": 3,
    "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": 40, "width": 8, "height": 6})" +
         extra + "}";
}
// A document with these objects.
std::string objects_doc(const std::string& objects) {
  return doc(R"(, "materials": {"m": {}}, "objects": [)" + objects + "]");
}

Scene parse_valid(const std::string& text, const std::string& path = "scene.json") {
  Expected<Scene> s = parse_scene(text, path);
  EXPECT_TRUE(s.ok()) << (s.ok() ? "" : s.error().message);
  return s.ok() ? std::move(*s) : Scene{};
}

void expect_vec3(Vec3 got, Vec3 want, float tolerance = 1e-5f) {
  EXPECT_NEAR(got.x, want.x, tolerance);
  EXPECT_NEAR(got.y, want.y, tolerance);
  EXPECT_NEAR(got.z, want.z, tolerance);
}

Bounds mesh_bounds(const TriangleMesh& m) {
  Scene s;
  s.meshes.push_back(m);
  return scene_bounds(s);
}

TEST(Scene3d, ParsesTheSpecExample) {
  const Scene s = parse_valid(kExample);
  EXPECT_EQ(s.source, "scene.json");
  expect_vec3(s.camera.position, {0, 1, 3.4f}, 0);
  expect_vec3(s.camera.look_at, {0, 1, 0}, 0);
  EXPECT_EQ(s.camera.fov_y, 40);
  EXPECT_EQ(s.camera.width, 640);
  EXPECT_EQ(s.camera.height, 480);
  EXPECT_EQ(s.sky.zenith.b, 1.0f);
  EXPECT_EQ(s.sky.horizon.r, 0.8f);
  EXPECT_EQ(s.sky.ground.g, 0.2f);
  ASSERT_TRUE(s.has_sun);
  const float len = std::sqrt(0.3f * 0.3f + 1 + 0.2f * 0.2f);
  expect_vec3(s.sun.direction, {0.3f / len, 1 / len, 0.2f / len}, 1e-6f);
  EXPECT_EQ(s.sun.irradiance.g, 5.5f);
  EXPECT_EQ(s.sun.angular_radius, 0.27f);

  // Named materials, then the sphere's inline one.
  ASSERT_EQ(s.materials.size(), 3u);
  std::vector<std::string> names;
  for (const Material& m : s.materials) names.push_back(m.name);
  EXPECT_EQ(names, (std::vector<std::string>{"lamp", "white", "objects[1].material"}));
  EXPECT_EQ(s.materials[0].emission.r, 17);
  EXPECT_EQ(s.materials[0].albedo.r, 0.8f);  // the default albedo
  EXPECT_EQ(s.materials[1].albedo.r, 0.73f);
  EXPECT_EQ(s.materials[2].albedo.g, 0.2f);

  ASSERT_EQ(s.objects.size(), 4u);
  EXPECT_EQ(s.objects[0], "objects[0] (box)");
  EXPECT_EQ(s.objects[1], "objects[1] (sphere)");
  EXPECT_EQ(s.objects[3], "objects[3] (disk)");

  ASSERT_EQ(s.meshes.size(), 2u);  // the box and the quad
  EXPECT_EQ(s.meshes[0].triangles.size(), 12u);
  EXPECT_EQ(s.meshes[0].object, 0);
  EXPECT_EQ(s.meshes[0].materials, std::vector<std::uint32_t>(12, 1));
  EXPECT_EQ(s.meshes[1].triangles.size(), 2u);
  EXPECT_EQ(s.meshes[1].object, 2);
  EXPECT_EQ(s.meshes[1].materials, std::vector<std::uint32_t>(2, 0));
  const Bounds quad = mesh_bounds(s.meshes[1]);
  expect_vec3(quad.lo, {-0.25f, 1.98f, -0.25f}, 0);
  expect_vec3(quad.hi, {0.25f, 1.98f, 0.25f}, 0);

  ASSERT_EQ(s.spheres.size(), 1u);
  expect_vec3(s.spheres[0].center, {-1, 0.4f, 0.5f}, 0);
  EXPECT_EQ(s.spheres[0].radius, 0.4f);
  EXPECT_EQ(s.spheres[0].material, 2u);
  EXPECT_EQ(s.spheres[0].object, 1);
  ASSERT_EQ(s.disks.size(), 1u);
  EXPECT_EQ(s.disks[0].radius, 10);
  expect_vec3(s.disks[0].normal, {0, 1, 0}, 0);
  EXPECT_EQ(s.disks[0].material, 1u);
  EXPECT_EQ(s.disks[0].object, 3);

  ASSERT_EQ(s.media.size(), 1u);
  expect_vec3(s.media[0].half_size, {2, 1, 2}, 0);
  EXPECT_EQ(s.media[0].extinction.r, 0.2f);
  EXPECT_EQ(s.media[0].extinction.b, 0.2f);
  EXPECT_EQ(s.media[0].albedo.g, 0.8f);
  EXPECT_EQ(s.media[0].emission.r, 0);
  expect_vec3(s.media[0].axes[0], {1, 0, 0}, 0);
  EXPECT_TRUE(check_scene(s).ok());
}

TEST(Scene3d, Defaults) {
  const Scene s = parse_valid(doc(R"(, "objects": [{"type": "sphere", "center": [0, 0, 0],
      "radius": 1}])"));
  expect_vec3(s.camera.up, {0, 1, 0}, 0);
  EXPECT_EQ(s.sky.zenith.r, 0);
  EXPECT_EQ(s.sky.ground.b, 0);
  EXPECT_FALSE(s.has_sun);
  // An object without a material gets the default one: albedo 0.8, no emission.
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_EQ(s.materials[0].name, "default");
  EXPECT_EQ(s.materials[0].albedo.g, 0.8f);
  EXPECT_EQ(s.materials[0].emission.r, 0);
  EXPECT_EQ(s.materials[0].metallic, 0);
  EXPECT_EQ(s.materials[0].roughness, 1);
  EXPECT_TRUE(s.materials[0].lambertian());
  EXPECT_TRUE(s.media.empty());
}

TEST(Scene3d, TheCameraMayComeFromAGltfFile) {
  const std::string file = "/usr/share/assimp/models/glTF2/cameras/Cameras.gltf";
  ASSERT_TRUE(fs::exists(file)) << "run scripts/install-deps.sh (assimp-testmodels)";
  auto with_camera = [&](const std::string& camera) {
    return R"({"penumbra": 1, "dimensions": 3, "camera": )" + camera +
           R"(, "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}]})";
  };
  // Cameras.gltf: camera 0 (perspective, yfov 0.7, aspectRatio 1) on a node at (0.5, 0.5, 3),
  // looking down -z.
  const Scene s = parse_valid(with_camera(R"({"gltf": ")" + file + R"(", "width": 64})"));
  expect_vec3(s.camera.position, {0.5f, 0.5f, 3});
  expect_vec3(s.camera.look_at, {0.5f, 0.5f, 2});
  expect_vec3(s.camera.up, {0, 1, 0});
  EXPECT_NEAR(s.camera.fov_y, 0.7 * 180 / std::numbers::pi, 1e-4);
  EXPECT_EQ(s.camera.width, 64);
  EXPECT_EQ(s.camera.height, 64);  // from the aspect ratio
  // The transform moves it as it would move the file's meshes.
  const Scene t = parse_valid(with_camera(R"({"gltf": ")" + file +
                                          R"(", "index": 0, "width": 64, "height": 32,
      "transform": {"translate": [1, 0, 0], "rotate": [0, 90, 0]}})"));
  expect_vec3(t.camera.position, {4, 0.5f, -0.5f}, 1e-5f);
  expect_vec3(t.camera.look_at, {3, 0.5f, -0.5f}, 1e-5f);
  EXPECT_EQ(t.camera.height, 32);
  // Refusals name the camera and what is wrong in the file.
  auto refused = [&](const std::string& camera) {
    const Expected<Scene> r = parse_scene(with_camera(camera), "scene.json");
    return r.ok() ? std::string("loaded") : r.error().message;
  };
  EXPECT_EQ(refused(R"({"gltf": ")" + file + R"(", "index": 1, "width": 64})"),
            "scene.json: camera.gltf: Cameras.gltf: cameras[1]: a orthographic camera (only "
            "perspective cameras are supported)");
  EXPECT_EQ(refused(R"({"gltf": ")" + file + R"(", "index": 5, "width": 64})"),
            "scene.json: camera.gltf: Cameras.gltf: cameras: camera 5 does not exist (2 cameras)");
  EXPECT_NE(refused(R"({"gltf": ")" + file + R"("})").find("camera.width"), std::string::npos);
  EXPECT_NE(refused(R"({"gltf": "x.obj", "width": 64})").find("camera.gltf: expected a glTF file"),
            std::string::npos);
}

TEST(Scene3d, GlossyMaterialsTakeMetallicAndRoughness) {
  const Scene s = parse_valid(doc(R"(, "materials": {
      "metal": {"albedo": [0.9, 0.6, 0.3], "metallic": 1, "roughness": 0.25},
      "plaster": {"albedo": [0.7, 0.7, 0.7], "metallic": 0, "roughness": 1}},
      "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "metal"},
                  {"type": "sphere", "center": [3, 0, 0], "radius": 1, "material": "plaster"}])"));
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_EQ(s.materials[0].metallic, 1);
  EXPECT_EQ(s.materials[0].roughness, 0.25f);
  EXPECT_FALSE(s.materials[0].lambertian());
  EXPECT_TRUE(s.materials[1].lambertian());  // version 1's meaning: old images do not change
}

TEST(Scene3d, UniformSkyAndDefaultSunRadius) {
  const Scene s = parse_valid(
      doc(R"(, "sky": [0.5, 0.25, 2], "sun": {"direction": [0, 0, -3], "irradiance": [1, 2, 3]})"));
  for (const Rgb& c : {s.sky.zenith, s.sky.horizon, s.sky.ground}) {
    EXPECT_EQ(c.r, 0.5f);
    EXPECT_EQ(c.g, 0.25f);
    EXPECT_EQ(c.b, 2);
  }
  expect_vec3(s.sun.direction, {0, 0, -1}, 0);
  EXPECT_EQ(s.sun.angular_radius, 0.27f);
}

TEST(Scene3d, CommentKeysAreAllowed) {
  const Scene s = parse_valid(doc(R"(, "comment": "c", "_x": 1, "description": "d",
      "sky": {"zenith": [0, 0, 0], "horizon": [0, 0, 0], "ground": [0, 0, 0], "_n": 2},
      "sun": {"direction": [0, 1, 0], "irradiance": [1, 1, 1], "comment": "noon"},
      "materials": {"_note": "not a material", "comment": "nor this", "w": {"albedo": [1, 1, 1], "_k": 0}},
      "objects": [{"type": "box", "center": [0, 0, 0], "size": [1, 1, 1], "material": "w",
                   "_why": "a box", "transform": {"scale": 2, "comment": "big"}}],
      "media": [{"center": [0, 0, 0], "size": [1, 1, 1], "extinction": 1, "albedo": [0, 0, 0],
                 "description": "fog"}])"));
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_EQ(s.materials[0].name, "w");
}

TEST(Scene3d, UniformScaleKeepsSpheresAndDisksExact) {
  const Scene s = parse_valid(objects_doc(R"(
      {"type": "sphere", "center": [1, 0, 0], "radius": 0.5,
       "transform": {"scale": 2, "rotate": [0, 0, 90], "translate": [0, 0, 3]}},
      {"type": "disk", "center": [1, 0, 0], "normal": [0, 2, 0], "radius": 1,
       "transform": {"scale": [3, 3, 3], "rotate": [90, 0, 0]}})"));
  ASSERT_EQ(s.spheres.size(), 1u);
  // scale: (2, 0, 0); rotate about z by 90 degrees: (0, 2, 0); translate.
  expect_vec3(s.spheres[0].center, {0, 2, 3});
  EXPECT_EQ(s.spheres[0].radius, 1);
  ASSERT_EQ(s.disks.size(), 1u);
  expect_vec3(s.disks[0].center, {3, 0, 0});
  expect_vec3(s.disks[0].normal, {0, 0, 1});  // +y turned about x by 90 degrees
  EXPECT_EQ(s.disks[0].radius, 3);
  EXPECT_TRUE(s.meshes.empty());
}

TEST(Scene3d, NonUniformScaleTessellatesAnEllipsoid) {
  const Scene s = parse_valid(objects_doc(R"({"type": "sphere", "center": [1, 0, 0], "radius": 2,
      "material": "m", "transform": {"scale": [1, 2, 3], "translate": [0, 1, 0]}})"));
  ASSERT_TRUE(s.spheres.empty());
  ASSERT_EQ(s.meshes.size(), 1u);
  const TriangleMesh& m = s.meshes[0];
  EXPECT_EQ(m.triangles.size(), 128u * 64 * 2 - 2 * 128);
  EXPECT_EQ(m.object, 0);
  ASSERT_EQ(m.normals.size(), m.positions.size());
  // Centre (1, 1, 0), semi-axes (2, 4, 6); the normal is the gradient of the implicit form.
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    const Vec3 q = m.positions[i] - Vec3{1, 1, 0};
    const Vec3 g = normalize(Vec3{q.x / 4, q.y / 16, q.z / 36});
    ASSERT_NEAR(q.x * q.x / 4 + q.y * q.y / 16 + q.z * q.z / 36, 1, 1e-5) << i;
    ASSERT_NEAR(dot(m.normals[i], g), 1, 1e-5) << i;
  }
  const Bounds b = scene_bounds(s);
  expect_vec3(b.lo, {-1, -3, -6});
  expect_vec3(b.hi, {3, 5, 6});
  EXPECT_TRUE(check_scene(s).ok());
}

TEST(Scene3d, NonUniformScaleTessellatesAnEllipse) {
  const Scene s = parse_valid(objects_doc(R"({"type": "disk", "center": [0, 0, 0],
      "normal": [0, 1, 0], "radius": 1, "transform": {"scale": [2, 1, 0.5]}})"));
  ASSERT_TRUE(s.disks.empty());
  ASSERT_EQ(s.meshes.size(), 1u);
  const TriangleMesh& m = s.meshes[0];
  EXPECT_EQ(m.triangles.size(), 256u);
  for (std::size_t i = 1; i < m.positions.size(); ++i) {
    const Vec3 p = m.positions[i];
    EXPECT_EQ(p.y, 0);
    ASSERT_NEAR(p.x * p.x / 4 + p.z * p.z / 0.25, 1, 1e-5);
    expect_vec3(m.normals[i], {0, 1, 0});
  }
}

TEST(Scene3d, BoxRotatesAboutItsCentreThenTheTransform) {
  // Long along x; its own rotate (z, 90) stands it up about its centre (2, 0, 0); then the
  // transform turns it about the world's y axis by 90 degrees: (x, y, z) -> (z, y, -x).
  const Scene s = parse_valid(objects_doc(R"({"type": "box", "center": [2, 0, 0],
      "size": [2, 1, 1], "rotate": [0, 0, 90], "transform": {"rotate": [0, 90, 0]}})"));
  ASSERT_EQ(s.meshes.size(), 1u);
  const Bounds b = mesh_bounds(s.meshes[0]);
  expect_vec3(b.lo, {-0.5f, -1, -2.5f});
  expect_vec3(b.hi, {0.5f, 1, -1.5f});
}

TEST(Scene3d, BoxFacesHaveOutwardFlatNormals) {
  const Scene s = parse_valid(
      objects_doc(R"({"type": "box", "center": [0, 0, 0], "size": [1, 2, 3], "material": "m"})"));
  ASSERT_EQ(s.meshes.size(), 1u);
  const TriangleMesh& m = s.meshes[0];
  ASSERT_EQ(m.triangles.size(), 12u);
  ASSERT_EQ(m.normals.size(), m.positions.size());
  for (const auto& t : m.triangles) {
    const Vec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
    const Vec3 n = normalize(cross(b - a, c - a));
    const Vec3 centroid = (a + b + c) / 3;
    EXPECT_GT(dot(n, centroid), 0);  // outwards from the centre
    for (std::uint32_t k : t) expect_vec3(m.normals[k], n);
  }
  const Bounds b = scene_bounds(s);
  expect_vec3(b.lo, {-0.5f, -1, -1.5f}, 0);
  expect_vec3(b.hi, {0.5f, 1, 1.5f}, 0);
}

TEST(Scene3d, QuadIsTwoTrianglesWithTheEdgesNormal) {
  const Scene s = parse_valid(objects_doc(
      R"({"type": "quad", "corner": [1, 2, 3], "u": [2, 0, 0], "v": [0, 0, -1],
          "transform": {"translate": [0, 1, 0]}})"));
  ASSERT_EQ(s.meshes.size(), 1u);
  const TriangleMesh& m = s.meshes[0];
  ASSERT_EQ(m.positions.size(), 4u);
  EXPECT_EQ(m.triangles.size(), 2u);
  expect_vec3(m.positions[0], {1, 3, 3}, 0);
  expect_vec3(m.positions[2], {3, 3, 2}, 0);
  expect_vec3(m.normals[0], {0, 1, 0});  // cross(u, v)
}

TEST(Scene3d, MediaTakeRotateAndGreyOrRgbExtinction) {
  const Scene s = parse_valid(doc(R"(, "media": [
      {"center": [1, 2, 3], "size": [2, 4, 6], "rotate": [0, 90, 0], "extinction": [0.1, 0.2, 0.3],
       "albedo": [0.5, 0.5, 0.5], "emission": [0, 1, 0]},
      {"type": "box", "center": [0, 0, 0], "size": [1, 1, 1], "extinction": 0, "albedo": [1, 1, 1]}])"));
  ASSERT_EQ(s.media.size(), 2u);
  const Medium& m = s.media[0];
  expect_vec3(m.half_size, {1, 2, 3}, 0);
  expect_vec3(m.axes[0], {0, 0, -1});
  expect_vec3(m.axes[1], {0, 1, 0});
  expect_vec3(m.axes[2], {1, 0, 0});
  EXPECT_EQ(m.extinction.b, 0.3f);
  EXPECT_EQ(m.emission.g, 1);
  EXPECT_EQ(s.media[1].extinction.g, 0);
}

TEST(Scene3d, ScaleOverflowIsRefused) {
  auto r = parse_scene(objects_doc(R"({"type": "sphere", "center": [3e38, 0, 0], "radius": 1,
      "transform": {"scale": 10}})"),
                       "scene.json");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message.rfind("scene.json: objects[0]: ", 0), 0u) << r.error().message;
  EXPECT_NE(r.error().message.find("past the largest world coordinate"), std::string::npos)
      << r.error().message;
}

TEST(Scene3d, MemoryLimitCoversShapes) {
  LoadOptions options;
  options.max_memory = 100000;  // one ellipsoid is about 460 KB
  auto r = parse_scene(objects_doc(R"({"type": "box", "center": [0, 0, 0], "size": [1, 1, 1]},
      {"type": "sphere", "center": [0, 0, 0], "radius": 1, "transform": {"scale": [1, 2, 1]}})"),
                       "scene.json", options);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message.rfind("scene.json: objects[1]: ", 0), 0u) << r.error().message;
  EXPECT_NE(r.error().message.find("memory limit"), std::string::npos) << r.error().message;
}

// ---- Error rules: each names the file and the JSON path. ----

using penumbra::testing::ErrorCase;

std::string camera_doc(const std::string& camera) {
  return R"({"penumbra": 1, "dimensions": 3, "camera": )" + camera + "}";
}
std::string object_doc(const std::string& object) {
  return objects_doc(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1}, )" + object);
}
// A document whose second object is a box with `extra` members.
std::string box_doc(const std::string& extra) {
  return object_doc(R"({"type": "box", "center": [0, 0, 0], "size": [1, 1, 1])" + extra + "}");
}

std::vector<ErrorCase> error_cases() {
  const std::string cam = R"("position": [0, 0, 5], "look_at": [0, 0, 0], "width": 8, "height": 6)";
  return {
      {"NotAnObject", "[1]", "(document)", "object"},
      {"MissingPenumbra", R"({"dimensions": 3})", "penumbra", "missing"},
      {"UnknownVersion", R"({"penumbra": 2, "dimensions": 3})", "penumbra", "unknown version"},
      {"VersionFloat", R"({"penumbra": 1.0, "dimensions": 3})", "penumbra", "found 1.0"},
      {"MissingDimensions", R"({"penumbra": 1})", "dimensions", "missing"},
      {"DimensionsTwo", R"({"penumbra": 1, "dimensions": 2})", "dimensions", "found 2"},
      {"DimensionsString", R"({"penumbra": 1, "dimensions": "3"})", "dimensions", "string"},
      {"UnknownTopKey", doc(R"(, "object": [])"), "object", "unknown key \"object\""},
      {"MissingCamera", R"({"penumbra": 1, "dimensions": 3})", "camera", "missing"},
      {"CameraNotObject", camera_doc("[]"), "camera", "an object"},
      {"CameraUnknownKey", camera_doc("{" + cam + R"(, "fov_y": 40, "fovy": 40})"), "camera.fovy",
       "unknown key"},
      {"CameraMissingPosition", camera_doc(R"({"look_at": [0, 0, 0], "fov_y": 40, "width": 8,
          "height": 6})"),
       "camera.position", "missing"},
      {"CameraPositionTwoNumbers", camera_doc(R"({"position": [0, 0], "look_at": [0, 0, 0],
          "fov_y": 40, "width": 8, "height": 6})"),
       "camera.position", "3 numbers"},
      {"CameraPositionInfinite", camera_doc(R"({"position": [0, 1e999, 5], "look_at": [0, 0, 0],
          "fov_y": 40, "width": 8, "height": 6})"),
       "camera.position[1]", "finite"},
      {"CameraLookAtEqualsPosition", camera_doc(R"({"position": [1, 2, 3], "look_at": [1, 2, 3],
          "fov_y": 40, "width": 8, "height": 6})"),
       "camera.look_at", "distinct"},
      {"CameraUpParallel", camera_doc("{" + cam + R"(, "fov_y": 40, "up": [0, 0, -2]})"),
       "camera.up", "not parallel"},
      {"CameraUpZero", camera_doc("{" + cam + R"(, "fov_y": 40, "up": [0, 0, 0]})"), "camera.up",
       "non-zero"},
      {"CameraMissingFov", camera_doc("{" + cam + "}"), "camera.fov_y", "missing"},
      {"CameraFovZero", camera_doc("{" + cam + R"(, "fov_y": 0})"), "camera.fov_y",
       "expected a number in (0, 180), found 0"},
      {"CameraFov180", camera_doc("{" + cam + R"(, "fov_y": 180})"), "camera.fov_y", "found 180"},
      {"CameraWidthZero", camera_doc(R"({"position": [0, 0, 5], "look_at": [0, 0, 0], "fov_y": 40,
          "width": 0, "height": 6})"),
       "camera.width", "expected an integer in 1..8192, found 0"},
      {"CameraHeightTooLarge", camera_doc(R"({"position": [0, 0, 5], "look_at": [0, 0, 0],
          "fov_y": 40, "width": 8, "height": 8193})"),
       "camera.height", "found 8193"},
      {"CameraWidthFloat", camera_doc(R"({"position": [0, 0, 5], "look_at": [0, 0, 0],
          "fov_y": 40, "width": 8.0, "height": 6})"),
       "camera.width", "found 8.0"},
      {"SkyNegative", doc(R"(, "sky": [1, -1, 0])"), "sky[1]", "found -1"},
      {"SkyNumber", doc(R"(, "sky": 1)"), "sky", "zenith"},
      {"SkyMissingGround", doc(R"(, "sky": {"zenith": [0, 0, 0], "horizon": [0, 0, 0]})"),
       "sky.ground", "missing"},
      {"SkyUnknownKey", doc(R"(, "sky": {"zenit": [0, 0, 0]})"), "sky.zenit", "unknown key"},
      {"SkyZenithNegative",
       doc(R"(, "sky": {"zenith": [0, 0, -2], "horizon": [0, 0, 0], "ground": [0, 0, 0]})"),
       "sky.zenith[2]", "found -2"},
      {"SunDirectionZero", doc(R"(, "sun": {"direction": [0, 0, 0], "irradiance": [1, 1, 1]})"),
       "sun.direction", "non-zero"},
      {"SunMissingIrradiance", doc(R"(, "sun": {"direction": [0, 1, 0]})"), "sun.irradiance",
       "missing"},
      {"SunIrradianceNegative",
       doc(R"(, "sun": {"direction": [0, 1, 0], "irradiance": [1, -1, 1]})"), "sun.irradiance[1]",
       "found -1"},
      {"SunRadiusZero",
       doc(R"(, "sun": {"direction": [0, 1, 0], "irradiance": [1, 1, 1], "angular_radius": 0})"),
       "sun.angular_radius", "expected a number in (0, 45], found 0"},
      {"SunRadiusAbove45",
       doc(R"(, "sun": {"direction": [0, 1, 0], "irradiance": [1, 1, 1], "angular_radius": 45.5})"),
       "sun.angular_radius", "found 45.5"},
      {"MaterialsNotObject", doc(R"(, "materials": [])"), "materials", "object"},
      {"MaterialAlbedoAboveOne", doc(R"(, "materials": {"w": {"albedo": [1, 1.5, 1]}})"),
       "materials.w.albedo[1]", "found 1.5"},
      {"MaterialEmissionNegative", doc(R"(, "materials": {"w": {"emission": [0, 0, -1]}})"),
       "materials.w.emission[2]", "found -1"},
      {"MaterialMetallicAboveOne", doc(R"(, "materials": {"w": {"metallic": 1.5}})"),
       "materials.w.metallic", "expected a number in [0, 1], found 1.5"},
      {"MaterialRoughnessNegative", doc(R"(, "materials": {"w": {"roughness": -0.1}})"),
       "materials.w.roughness", "found -0.1"},
      {"MaterialRoughnessNotNumber", doc(R"(, "materials": {"w": {"roughness": "low"}})"),
       "materials.w.roughness", "number"},
      {"MaterialUnknownKey", doc(R"(, "materials": {"w": {"color": [1, 1, 1]}})"),
       "materials.w.color", "unknown key"},
      {"MaterialNotObject", doc(R"(, "materials": {"w": [1, 1, 1]})"), "materials.w",
       "material object"},
      {"UnknownMaterialName", box_doc(R"(, "material": "whit")"), "objects[1].material",
       "unknown material \"whit\", expected one of: m"},
      {"InlineMaterialAlbedoNegative", box_doc(R"(, "material": {"albedo": [-1, 0, 0]})"),
       "objects[1].material.albedo[0]", "found -1"},
      {"MaterialNumber", box_doc(R"(, "material": 3)"), "objects[1].material", "material name"},
      {"ObjectsNotArray", doc(R"(, "objects": {})"), "objects", "array"},
      {"ObjectNotObject", object_doc("3"), "objects[1]", "object"},
      {"MissingType", object_doc(R"({"center": [0, 0, 0], "radius": 1})"), "objects[1].type",
       "missing"},
      {"UnknownType", object_doc(R"({"type": "cone"})"), "objects[1].type",
       "unknown object type \"cone\""},
      {"UnknownObjectKey", object_doc(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1,
          "radus": 2})"),
       "objects[1].radus", "unknown key \"radus\""},
      {"SphereRadiusZero", object_doc(R"({"type": "sphere", "center": [0, 0, 0], "radius": 0})"),
       "objects[1].radius", "expected a number > 0, found 0"},
      {"SphereMissingCenter", object_doc(R"({"type": "sphere", "radius": 1})"), "objects[1].center",
       "missing"},
      {"BoxSizeNegative", object_doc(R"({"type": "box", "center": [0, 0, 0], "size": [1, -1, 1]})"),
       "objects[1].size[1]", "found -1"},
      {"BoxSizeTwoNumbers", object_doc(R"({"type": "box", "center": [0, 0, 0], "size": [1, 1]})"),
       "objects[1].size", "3 numbers > 0"},
      {"BoxRotateString", box_doc(R"(, "rotate": "90")"), "objects[1].rotate", "string"},
      {"QuadParallel",
       object_doc(R"({"type": "quad", "corner": [0, 0, 0], "u": [1, 2, 3], "v": [-2, -4, -6]})"),
       "objects[1].v", "not parallel"},
      {"QuadZeroEdge",
       object_doc(R"({"type": "quad", "corner": [0, 0, 0], "u": [0, 0, 0], "v": [0, 1, 0]})"),
       "objects[1].v", "non-zero"},
      {"QuadMissingV", object_doc(R"({"type": "quad", "corner": [0, 0, 0], "u": [1, 0, 0]})"),
       "objects[1].v", "missing"},
      {"DiskNormalZero",
       object_doc(R"({"type": "disk", "center": [0, 0, 0], "normal": [0, 0, 0], "radius": 1})"),
       "objects[1].normal", "non-zero"},
      {"DiskRadiusNegative",
       object_doc(R"({"type": "disk", "center": [0, 0, 0], "normal": [0, 1, 0], "radius": -1})"),
       "objects[1].radius", "found -1"},
      {"MeshMissingFile", object_doc(R"({"type": "mesh"})"), "objects[1].file", "missing"},
      {"MeshFileNumber", object_doc(R"({"type": "mesh", "file": 3})"), "objects[1].file",
       "found 3"},
      {"MeshFileExtension", object_doc(R"({"type": "mesh", "file": "bunny.ply"})"),
       "objects[1].file", ".obj, .gltf or .glb"},
      {"MeshFileAbsent", object_doc(R"({"type": "mesh", "file": "no_such_mesh.obj"})"),
       "objects[1].file", "no_such_mesh.obj"},
      {"TransformNotObject", box_doc(R"(, "transform": [1])"), "objects[1].transform", "object"},
      {"TransformUnknownKey", box_doc(R"(, "transform": {"scal": 2})"), "objects[1].transform.scal",
       "unknown key"},
      {"TransformScaleZero", box_doc(R"(, "transform": {"scale": 0})"),
       "objects[1].transform.scale", "found 0"},
      {"TransformScaleNegativeComponent", box_doc(R"(, "transform": {"scale": [1, 1, -2]})"),
       "objects[1].transform.scale[2]", "found -2"},
      {"TransformScaleTwoNumbers", box_doc(R"(, "transform": {"scale": [1, 2]})"),
       "objects[1].transform.scale", "a number > 0 or an array of 3 numbers > 0"},
      {"TransformRotateTwoNumbers", box_doc(R"(, "transform": {"rotate": [1, 2]})"),
       "objects[1].transform.rotate", "3 numbers"},
      {"TransformTranslateNull", box_doc(R"(, "transform": {"translate": [1, null, 2]})"),
       "objects[1].transform.translate[1]", "null"},
      {"MediaNotArray", doc(R"(, "media": {})"), "media", "array"},
      {"MediumUnknownType", doc(R"(, "media": [{"type": "sphere"}])"), "media[0].type",
       "expected box"},
      {"MediumMissingExtinction",
       doc(R"(, "media": [{"center": [0, 0, 0], "size": [1, 1, 1], "albedo": [0, 0, 0]}])"),
       "media[0].extinction", "missing"},
      {"MediumExtinctionNegative", doc(R"(, "media": [{"center": [0, 0, 0], "size": [1, 1, 1],
          "extinction": -1, "albedo": [0, 0, 0]}])"),
       "media[0].extinction", "found -1"},
      {"MediumExtinctionString", doc(R"(, "media": [{"center": [0, 0, 0], "size": [1, 1, 1],
          "extinction": "1", "albedo": [0, 0, 0]}])"),
       "media[0].extinction", "string"},
      {"MediumAlbedoAboveOne", doc(R"(, "media": [{"center": [0, 0, 0], "size": [1, 1, 1],
          "extinction": 1, "albedo": [0, 2, 0]}])"),
       "media[0].albedo[1]", "found 2"},
      {"MediumMissingAlbedo",
       doc(R"(, "media": [{"center": [0, 0, 0], "size": [1, 1, 1], "extinction": 1}])"),
       "media[0].albedo", "missing"},
      {"MediumSizeZero", doc(R"(, "media": [{"center": [0, 0, 0], "size": [1, 0, 1],
          "extinction": 1, "albedo": [0, 0, 0]}])"),
       "media[0].size[1]", "found 0"},
      {"MediumUnknownKey", doc(R"(, "media": [{"center": [0, 0, 0], "size": [1, 1, 1],
          "extinction": 1, "albedo": [0, 0, 0], "transform": {}}])"),
       "media[0].transform", "unknown key"},
      {"TooLargeForFloat",
       object_doc(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1e300})"),
       "objects[1].radius", "finite"},
      // Past the world's bound (1e15): Embree asserted on such rays and bounds (issue 37).
      {"CameraPastTheWorld", camera_doc(R"({"position": [1.9e18, 0, 5], "look_at": [0, 0, 0],
          "fov_y": 40, "width": 8, "height": 6})"),
       "camera.position", "the camera reaches x = 1.9e+18, past the largest world coordinate"},
      {"LookAtPastTheWorld", camera_doc(R"({"position": [0, 0, 5], "look_at": [0, -2e15, 0],
          "fov_y": 40, "width": 8, "height": 6})"),
       "camera.look_at", "reaches y = -2e+15"},
      {"SpherePastTheWorld",
       object_doc(R"({"type": "sphere", "center": [1e30, 0, 0], "radius": 1})"), "objects[1]",
       "the sphere (after its transform) reaches x = 1e+30"},
      {"SphereRadiusPastTheWorld",
       object_doc(R"({"type": "sphere", "center": [0, 0, 0], "radius": 2e15})"), "objects[1]",
       "reaches x = -2e+15"},
      {"DiskPastTheWorld", object_doc(R"({"type": "disk", "center": [0, 0, 0], "normal": [0, 1, 0],
          "radius": 1e30})"),
       "objects[1]", "the disk (after its transform) reaches x = -1e+30"},
      {"BoxPastTheWorld", box_doc(R"(, "transform": {"translate": [1e19, 0, 0]})"), "objects[1]",
       "the box (after its transform) reaches x = 1e+19"},
      {"ScalePastTheWorld", box_doc(R"(, "transform": {"scale": 1e30})"), "objects[1]",
       "the box (after its transform)"},
      {"EllipsoidPastTheWorld", object_doc(R"({"type": "sphere", "center": [0, 0, 0],
          "radius": 1, "transform": {"scale": [1, 1e30, 1]}})"),
       "objects[1]", "the sphere (after its transform) reaches y"},
      {"MediumPastTheWorld", doc(R"(, "media": [{"center": [1e30, 0, 0], "size": [1, 1, 1],
          "extinction": 1, "albedo": [0, 0, 0]}])"),
       "media[0]", "the fog box reaches x = 1e+30"},
      {"RotatedMediumPastTheWorld", doc(R"(, "media": [{"center": [0, 0, 0],
          "size": [3e15, 1, 1], "rotate": [0, 0, 90], "extinction": 1, "albedo": [0, 0, 0]}])"),
       "media[0]", "the fog box reaches y"},
  };
}

class Scene3dErrors : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(Scene3dErrors, NamesFileAndPath) {
  const ErrorCase& c = GetParam();
  auto r = parse_scene(c.json, "scene.json");
  penumbra::testing::expect_refused(r.ok(), r.ok() ? "" : r.error().message, c);
}

INSTANTIATE_TEST_SUITE_P(Scene3d, Scene3dErrors, ::testing::ValuesIn(error_cases()),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(Scene3d, SyntaxErrorNamesLineAndColumn) {
  auto r = parse_scene("{\n  \"penumbra\": 1,,\n}", "scene.json");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message.rfind("scene.json: line 2, column 17: invalid JSON", 0), 0u)
      << r.error().message;
}

TEST(Scene3d, LoadSceneReadsFileAndNamesMissingOnes) {
  TempDir dir;
  auto r = load_scene(dir.write("s.json", kExample));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->source, dir.file("s.json"));
  const std::string missing = dir.file("nope.json");
  auto m = load_scene(missing);
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(m.error().message, missing + ": cannot read the scene file: no such file");
}

TEST(Scene3d, Dimensions) {
  TempDir dir;
  auto dims = [&](const std::string& text) { return scene_dimensions(dir.write("d.json", text)); };
  EXPECT_EQ(*dims(R"({"penumbra": 1, "width": 4, "height": 4})"), 2);
  EXPECT_EQ(*dims(R"({"penumbra": 1, "dimensions": 2})"), 2);
  EXPECT_EQ(*dims(kExample), 3);
  auto four = dims(R"({"penumbra": 1, "dimensions": 4})");
  ASSERT_FALSE(four.ok());
  EXPECT_EQ(four.error().message,
            dir.file("d.json") + ": dimensions: expected the integer 2 or 3, found 4");
  auto text = dims(R"({"dimensions": "3"})");
  ASSERT_FALSE(text.ok());
  EXPECT_NE(text.error().message.find(": dimensions: "), std::string::npos);
  auto bad = dims("{,}");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("line 1, column 2: invalid JSON"), std::string::npos)
      << bad.error().message;
  auto missing = scene_dimensions(dir.file("none.json"));
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().message,
            dir.file("none.json") + ": cannot read the scene file: no such file");
}

// A cube written as OBJ, 8 vertices and 12 triangles, no MTL.
constexpr const char* kCubeObj = R"(v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 4 7 3
f 4 8 7
f 1 5 8
f 1 8 4
f 2 3 7
f 2 7 6
)";

TEST(Scene3d, MeshPathIsRelativeToTheSceneFile) {
  TempDir dir;
  fs::create_directories(dir.root() / "models");
  dir.write("models/cube.obj", kCubeObj);
  const std::string scene = dir.write("s.json", objects_doc(R"(
      {"type": "mesh", "file": "models/cube.obj", "material": "m",
       "transform": {"scale": 0.5, "translate": [0, 2, 0]}},
      {"type": "mesh", "file": "models/cube.obj"})"));
  auto r = load_scene(scene);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->meshes.size(), 2u);
  EXPECT_EQ(r->objects[0], "objects[0] (mesh)");
  EXPECT_EQ(r->meshes[0].triangles.size(), 12u);
  EXPECT_EQ(r->meshes[0].object, 0);
  EXPECT_EQ(r->meshes[1].object, 1);
  // The override gives every triangle the named material; without it the file's own default
  // material is appended after the scene's.
  EXPECT_EQ(r->meshes[0].materials, std::vector<std::uint32_t>(12, 0));
  ASSERT_EQ(r->materials.size(), 2u);
  EXPECT_EQ(r->meshes[1].materials, std::vector<std::uint32_t>(12, 1));
  // A file used again is parsed once: its materials join the scene once, each object has its
  // own triangles.
  const std::string thrice = dir.write("t.json", objects_doc(R"(
      {"type": "mesh", "file": "models/cube.obj"},
      {"type": "mesh", "file": "models/cube.obj", "transform": {"translate": [3, 0, 0]}},
      {"type": "mesh", "file": "models/../models/cube.obj", "material": "m"})"));
  auto t = load_scene(thrice);
  ASSERT_TRUE(t.ok()) << t.error().message;
  ASSERT_EQ(t->meshes.size(), 3u);
  EXPECT_EQ(t->materials.size(), 2u);
  EXPECT_EQ(t->meshes[0].materials, t->meshes[1].materials);
  EXPECT_EQ(mesh_bounds(t->meshes[1]).lo.x, mesh_bounds(t->meshes[0]).lo.x + 3);
  EXPECT_EQ(t->meshes[2].materials, std::vector<std::uint32_t>(12, 0));
  // Used first with a material of its own, then with the file's: those join at the second.
  const std::string override_first = dir.write("o.json", objects_doc(R"(
      {"type": "mesh", "file": "models/cube.obj", "material": "m"},
      {"type": "mesh", "file": "models/cube.obj"})"));
  auto o = load_scene(override_first);
  ASSERT_TRUE(o.ok()) << o.error().message;
  EXPECT_EQ(o->materials.size(), 2u);
  EXPECT_EQ(o->meshes[0].materials, std::vector<std::uint32_t>(12, 0));
  EXPECT_EQ(o->meshes[1].materials, std::vector<std::uint32_t>(12, 1));
  const Bounds b = mesh_bounds(r->meshes[0]);
  expect_vec3(b.lo, {-0.5f, 1.5f, -0.5f});
  expect_vec3(b.hi, {0.5f, 2.5f, 0.5f});
  // From another directory, the same relative name is not found.
  auto elsewhere = parse_scene(objects_doc(R"({"type": "mesh", "file": "models/cube.obj"})"),
                               "elsewhere/s.json");
  ASSERT_FALSE(elsewhere.ok());
  EXPECT_EQ(elsewhere.error().message.rfind("elsewhere/s.json: objects[0].file: ", 0), 0u)
      << elsewhere.error().message;
}

TEST(Scene3d, ExampleScenesParse) {
  const fs::path folder = fs::path(PENUMBRA_SOURCE_DIR) / "scenes" / "3d";
  int count = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() != ".json") continue;
    ++count;
    auto r = load_scene(entry.path().string());
    EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
    if (!r.ok()) continue;
    EXPECT_TRUE(check_scene(*r).ok());
    EXPECT_FALSE(r->objects.empty()) << entry.path();
    EXPECT_LE(r->camera.width * r->camera.height, 400 * 300) << entry.path();
    auto d = scene_dimensions(entry.path().string());
    ASSERT_TRUE(d.ok());
    EXPECT_EQ(*d, 3);
  }
  EXPECT_GE(count, 10);
}

// ---- Scenes built in code. ----

Scene code_scene() {
  Scene s;
  s.materials.push_back(Material{});
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  m.materials = {0};
  s.meshes.push_back(m);
  s.spheres.push_back(Sphere{{0, 0, 0}, 1, 0, -1});
  s.disks.push_back(Disk{{0, 0, 0}, {0, 1, 0}, 1, 0, -1});
  s.media.push_back(Medium{});
  return s;
}

TEST(Scene3dCheck, AcceptsAValidScene) {
  const Status st = check_scene(code_scene());
  EXPECT_TRUE(st.ok()) << st.error().message;
}

TEST(Scene3dCheck, NamesTheField) {
  struct Case {
    const char* name;
    void (*mutate)(Scene&);
    std::string message;
  };
  const std::vector<Case> cases = {
      {"TriangleIndex",
       [](Scene& s) {
         s.meshes[0].triangles.push_back({0, 1, 9});
       },
       "<code>: meshes[0].triangles[1]: index 9 out of range (3 positions)"},
      {"MaterialsPerTriangle", [](Scene& s) { s.meshes[0].materials.clear(); },
       "<code>: meshes[0].materials: expected one per triangle (1), found 0"},
      {"MaterialIndex", [](Scene& s) { s.meshes[0].materials[0] = 1; },
       "<code>: meshes[0].materials[0]: material 1 out of range (1 materials)"},
      {"NormalsCount",
       [](Scene& s) {
         s.meshes[0].normals = {{0, 0, 1}};
       },
       "<code>: meshes[0].normals: expected none or one per position (3), found 1"},
      {"NormalNotUnit",
       [](Scene& s) {
         s.meshes[0].normals.assign(3, {0, 0, 2});
       },
       "<code>: meshes[0].normals[0]: expected a unit vector, found [0, 0, 2] (length 2)"},
      {"UvsCount",
       [](Scene& s) {
         s.meshes[0].uvs = {{0, 0}};
       },
       "<code>: meshes[0].uvs: expected none or one per position (3), found 1"},
      {"LightmapUvsCount",
       [](Scene& s) {
         s.meshes[0].lightmap_uvs = {{0, 0}};
       },
       "<code>: meshes[0].lightmap_uvs: expected none or one per position (3), found 1"},
      {"LightmapUvNan",
       [](Scene& s) {
         s.meshes[0].lightmap_uvs.assign(3, {0, 0});
         s.meshes[0].lightmap_uvs[1][0] = std::nanf("");
       },
       "<code>: meshes[0].lightmap_uvs[1][0]: expected a finite number, found nan"},
      {"PositionNan", [](Scene& s) { s.meshes[0].positions[2].y = std::nanf(""); },
       "<code>: meshes[0].positions[2][1]: expected a finite number, found nan"},
      {"TextureIndex", [](Scene& s) { s.materials[0].albedo_texture.index = 0; },
       "<code>: materials[0].albedo_texture.index: texture 0 out of range (-1 or one of the 0 "
       "textures)"},
      {"AlbedoAboveOne", [](Scene& s) { s.materials[0].albedo.g = 1.5f; },
       "<code>: materials[0].albedo[1]: expected a number in [0, 1], found 1.5"},
      {"SphereRadius", [](Scene& s) { s.spheres[0].radius = 0; },
       "<code>: spheres[0].radius: expected a number > 0, found 0"},
      {"DiskNormal",
       [](Scene& s) {
         s.disks[0].normal = {0, 0.5f, 0};
       },
       "<code>: disks[0].normal: expected a unit vector, found [0, 0.5, 0] (length 0.5)"},
      {"DiskMaterial", [](Scene& s) { s.disks[0].material = 4; },
       "<code>: disks[0].material: material 4 out of range (1 materials)"},
      {"ObjectIndex", [](Scene& s) { s.spheres[0].object = 0; },
       "<code>: spheres[0].object: object 0 out of range (-1 or one of the 0 objects)"},
      {"MediumAxes",
       [](Scene& s) {
         s.media[0].axes[1] = {1, 0, 0};
       },
       "<code>: media[0].axes: expected orthogonal axes, found axes 0 and 1 with dot product 1"},
      {"CameraFov", [](Scene& s) { s.camera.fov_y = 180; },
       "<code>: camera.fov_y: expected a number in (0, 180), found 180"},
      {"CameraUp",
       [](Scene& s) {
         s.camera.up = {0, 0, 1};
       },
       "<code>: camera.up: expected a non-zero vector not parallel to the view direction "
       "(look_at - position), found [0, 0, 1]"},
      {"CameraWidth", [](Scene& s) { s.camera.width = 8193; },
       "<code>: camera.width: expected an integer in 1..8192, found 8193"},
      {"SunDirection",
       [](Scene& s) {
         s.has_sun = true;
         s.sun.direction = {0, 2, 0};
       },
       "<code>: sun.direction: expected a unit vector, found [0, 2, 0] (length 2)"},
      {"SunRadius",
       [](Scene& s) {
         s.has_sun = true;
         s.sun.angular_radius = 50;
       },
       "<code>: sun.angular_radius: expected a number in (0, 45], found 50"},
      {"SkyNegative", [](Scene& s) { s.sky.ground.b = -1; },
       "<code>: sky.ground[2]: expected a number >= 0, found -1"},
  };
  for (const Case& c : cases) {
    Scene s = code_scene();
    c.mutate(s);
    const Status st = check_scene(s);
    ASSERT_FALSE(st.ok()) << c.name;
    EXPECT_EQ(st.error().message, c.message) << c.name;
  }
}

TEST(Scene3dCheck, BoundsAreExactForSpheresAndDisks) {
  Scene s;
  EXPECT_EQ(scene_bounds(s).lo, (Vec3{0, 0, 0}));
  EXPECT_EQ(scene_bounds(s).hi, (Vec3{0, 0, 0}));
  s.spheres.push_back(Sphere{{1, 2, 3}, 0.5f, 0, -1});
  const float h = std::sqrt(0.5f);
  s.disks.push_back(Disk{{0, 0, 0}, {h, h, 0}, 2, 0, -1});
  const Bounds b = scene_bounds(s);
  // The tilted disk spans radius * sqrt(1 - n_i^2) along each axis: sqrt(2), sqrt(2), 2.
  expect_vec3(b.lo, {-std::sqrt(2.0f), -std::sqrt(2.0f), -2});
  expect_vec3(b.hi, {1.5f, 2.5f, 3.5f});
}

TEST(Scene3dCheck, BytesCountTheArrays) {
  Scene s;
  const std::uint64_t empty = scene_bytes(s);
  EXPECT_EQ(empty, 0u);
  TriangleMesh m;
  m.positions.resize(10);
  m.normals.resize(10);
  m.uvs.resize(10);
  m.lightmap_uvs.resize(10);
  m.triangles.resize(4);
  m.materials.resize(4);
  s.meshes.push_back(m);
  Texture t;
  t.rgb.resize(300);
  s.textures.push_back(t);
  EXPECT_EQ(scene_bytes(s), 10u * 12 + 10 * 12 + 2 * 10 * 8 + 4 * 12 + 4 * 4 + 300 * 4);
}

TEST(Scene3dTransform, NormalsStayOrthogonalToTheTransformedSurface) {
  const Affine a = Affine::trs({1, 2, 3}, {30, 50, 70}, {4, 5, 6});
  const Vec3 t1{1, 2, -1}, t2{0.5f, -1, 2};
  const Vec3 n = a.normal(normalize(cross(t1, t2)));
  EXPECT_NEAR(length(n), 1, 1e-6);
  EXPECT_NEAR(dot(n, a.direction(t1)), 0, 1e-5);
  EXPECT_NEAR(dot(n, a.direction(t2)), 0, 1e-5);
  EXPECT_GT(dot(n, cross(a.direction(t1), a.direction(t2))), 0);  // the same side
  // A pure rotation turns normals as it turns points.
  const Affine r = Affine::rotate(0, 90);
  expect_vec3(r.normal({0, 1, 0}), r.direction({0, 1, 0}));
}

// ---- Real mesh files: these need the mesh file reader (mesh_file.cpp). ----

TEST(Scene3dMeshFile, ReadsTheBunny) {
  if (!fs::exists(kBunny)) GTEST_SKIP() << kBunny << " is not installed";
  const Scene s = parse_valid(objects_doc(std::string(R"({"type": "mesh", "file": ")") + kBunny +
                                          R"(", "material": "m"})"));
  ASSERT_EQ(s.meshes.size(), 1u);
  EXPECT_GT(s.meshes[0].triangles.size(), 1000u);
  EXPECT_EQ(s.meshes[0].materials.size(), s.meshes[0].triangles.size());
}

TEST(Scene3dMeshFile, MemoryLimitReachesTheReader) {
  if (!fs::exists(kBunny)) GTEST_SKIP() << kBunny << " is not installed";
  LoadOptions options;
  options.max_memory = 10000;
  auto r = parse_scene(objects_doc(std::string(R"({"type": "mesh", "file": ")") + kBunny + "\"}"),
                       "scene.json", options);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message.rfind("scene.json: objects[0].file: ", 0), 0u) << r.error().message;
}

TEST(Scene3dMeshFile, EmptyMeshIsAnError) {
  TempDir dir;
  dir.write("empty.obj", "# nothing\nv 0 0 0\n");
  auto r = load_scene(dir.write("s.json", objects_doc(R"({"type": "mesh", "file": "empty.obj"})")));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message.rfind(dir.file("s.json") + ": objects[0].file: ", 0), 0u)
      << r.error().message;
  EXPECT_NE(r.error().message.find("empty.obj"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace penumbra::spaceland
