// The scene document: parsing, defaults, every error rule and the image layers.
#include "penumbra/flatland/scene.hpp"

#include <gtest/gtest.h>
#include <stb/stb_image_write.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace penumbra::flatland {
namespace {

namespace fs = std::filesystem;

// The spec's example document, without its layers.
constexpr const char* kExample = R"({
  "penumbra": 1,
  "width": 512,
  "height": 512,
  "environment": [0.0, 0.0, 0.0],
  "shapes": [
    { "type": "circle", "center": [128, 256], "radius": 12, "emission": [4, 3, 2] },
    { "type": "box", "center": [256, 256], "size": [14, 120], "angle": 0 },
    { "type": "segment", "a": [10, 10], "b": [200, 40], "width": 3, "albedo": [0.8, 0.8, 0.8] },
    { "type": "polygon", "points": [[300, 300], [340, 300], [320, 340]], "opacity": 0.2 }
  ]
})";

// A directory of the test's own, removed at the end.
struct TempDir : testing::TestDir {
  TempDir() : testing::TestDir("scene") {}
};

// A PFM written by hand: header, then little-endian float32 RGB, bottom row first.
// `rgb` is given top row first, like every image in the project.
void write_pfm(const std::string& path, int w, int h, const std::vector<float>& rgb) {
  std::ofstream out(path, std::ios::binary);
  out << "PF\n" << w << " " << h << "\n-1.0\n";
  for (int y = h - 1; y >= 0; --y) {
    for (int i = 0; i < w * 3; ++i) {
      float v = rgb[std::size_t(y) * w * 3 + i];
      unsigned char b[4];
      std::memcpy(b, &v, 4);  // the test machines are little-endian, as PFM "-1.0" says
      out.write(reinterpret_cast<const char*>(b), 4);
    }
  }
}

// The sRGB decoding curve, written out here as an independent reference.
double srgb_decode(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

std::string scene_doc(const std::string& extra) {
  return R"({"penumbra": 1, "width": 4, "height": 2)" + extra + "}";
}

TEST(Scene, ParsesTheSpecExample) {
  auto r = parse_scene(kExample, "scene.json");
  ASSERT_TRUE(r.ok()) << r.error().message;
  const SceneDesc& d = *r;
  EXPECT_EQ(d.width, 512);
  EXPECT_EQ(d.height, 512);
  EXPECT_EQ(d.source, "scene.json");
  ASSERT_EQ(d.shapes.size(), 4u);

  const auto& c = std::get<Circle>(d.shapes[0].geometry);
  EXPECT_FLOAT_EQ(c.center[0], 128);
  EXPECT_FLOAT_EQ(c.center[1], 256);
  EXPECT_FLOAT_EQ(c.radius, 12);
  EXPECT_FLOAT_EQ(d.shapes[0].material.emission.r, 4);
  EXPECT_FLOAT_EQ(d.shapes[0].material.emission.g, 3);
  EXPECT_FLOAT_EQ(d.shapes[0].material.emission.b, 2);
  EXPECT_FLOAT_EQ(d.shapes[0].material.opacity, 1);

  const auto& b = std::get<Box>(d.shapes[1].geometry);
  EXPECT_FLOAT_EQ(b.center[0], 256);
  EXPECT_FLOAT_EQ(b.size[0], 14);
  EXPECT_FLOAT_EQ(b.size[1], 120);
  EXPECT_FLOAT_EQ(b.angle, 0);

  const auto& s = std::get<Segment>(d.shapes[2].geometry);
  EXPECT_FLOAT_EQ(s.a[0], 10);
  EXPECT_FLOAT_EQ(s.a[1], 10);
  EXPECT_FLOAT_EQ(s.b[0], 200);
  EXPECT_FLOAT_EQ(s.b[1], 40);
  EXPECT_FLOAT_EQ(s.width, 3);
  EXPECT_FLOAT_EQ(d.shapes[2].material.albedo.r, 0.8f);
  EXPECT_FLOAT_EQ(d.shapes[2].material.albedo.b, 0.8f);

  const auto& p = std::get<Polygon>(d.shapes[3].geometry);
  ASSERT_EQ(p.points.size(), 3u);
  EXPECT_FLOAT_EQ(p.points[2][0], 320);
  EXPECT_FLOAT_EQ(p.points[2][1], 340);
  EXPECT_FLOAT_EQ(d.shapes[3].material.opacity, 0.2f);
}

TEST(Scene, Defaults) {
  auto r =
      parse_scene(scene_doc(R"(, "shapes": [{"type": "box", "center": [1, 1], "size": [2, 1]}])"),
                  "scene.json");
  ASSERT_TRUE(r.ok()) << r.error().message;
  const SceneDesc& d = *r;
  EXPECT_EQ(d.environment.r, 0);
  EXPECT_EQ(d.environment.g, 0);
  EXPECT_EQ(d.environment.b, 0);
  EXPECT_FALSE(d.layers.emission || d.layers.opacity || d.layers.albedo);
  ASSERT_EQ(d.shapes.size(), 1u);
  EXPECT_EQ(std::get<Box>(d.shapes[0].geometry).angle, 0);
  const Material& m = d.shapes[0].material;
  EXPECT_EQ(m.opacity, 1);
  EXPECT_EQ(m.emission.r + m.emission.g + m.emission.b, 0);
  EXPECT_EQ(m.albedo.r + m.albedo.g + m.albedo.b, 0);
  // No shapes at all is a valid (empty) scene.
  EXPECT_TRUE(parse_scene(scene_doc(""), "scene.json").ok());
}

TEST(Scene, EmissionScaleDefaultsToOne) {
  TempDir dir;
  write_pfm(dir.file("e.pfm"), 4, 2, std::vector<float>(24, 0.5f));
  auto r = load_scene(dir.write("scene.json", scene_doc(R"(, "layers": {"emission": "e.pfm"})")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_FLOAT_EQ(r->layers.emission->at(3, 1).g, 0.5f);
}

TEST(Scene, CommentKeysAreAllowed) {
  auto r = parse_scene(scene_doc(R"(, "comment": "hi", "_note": 3, "description": "d",
        "layers": {"_x": 1}, "shapes": [{"type": "circle", "center": [1, 1], "radius": 1,
        "comment": "a light", "_todo": [1, 2]}])"),
                       "scene.json");
  EXPECT_TRUE(r.ok()) << r.error().message;
}

// ---- Error rules: each names the file and the JSON path. ----

using penumbra::testing::ErrorCase;

std::string shape_doc(const std::string& shape) {
  return scene_doc(R"(, "shapes": [{"type": "circle", "center": [1, 1], "radius": 1}, )" + shape +
                   "]");
}

std::vector<ErrorCase> error_cases() {
  return {
      {"UnknownVersion", R"({"penumbra": 2, "width": 4, "height": 2})", "penumbra",
       "unknown version"},
      {"VersionNotInteger", R"({"penumbra": "1", "width": 4, "height": 2})", "penumbra", "1"},
      {"MissingPenumbra", R"({"width": 4, "height": 2})", "penumbra", "missing"},
      {"MissingWidth", R"({"penumbra": 1, "height": 2})", "width", "missing"},
      {"MissingHeight", R"({"penumbra": 1, "width": 4})", "height", "missing"},
      {"WidthZero", R"({"penumbra": 1, "width": 0, "height": 2})", "width", "found 0"},
      {"WidthTooLarge", R"({"penumbra": 1, "width": 16385, "height": 2})", "width", "found 16385"},
      {"HeightNegative", R"({"penumbra": 1, "width": 4, "height": -3})", "height", "found -3"},
      {"WidthFloat", R"({"penumbra": 1, "width": 4.5, "height": 2})", "width", "integer"},
      {"WidthIntegralFloat", R"({"penumbra": 1, "width": 4.0, "height": 2})", "width", "found 4.0"},
      {"WidthString", R"({"penumbra": 1, "width": "4", "height": 2})", "width", "string"},
      {"NotAnObject", R"([1, 2])", "(document)", "object"},
      {"StringForNumber", shape_doc(R"({"type": "circle", "center": [1, 1], "radius": "2"})"),
       "shapes[1].radius", "string"},
      {"EnvironmentTwoNumbers", scene_doc(R"(, "environment": [1, 2])"), "environment",
       "3 numbers"},
      {"EnvironmentNegative", scene_doc(R"(, "environment": [1, -0.5, 0])"), "environment[1]",
       "found -0.5"},
      {"UnknownShapeType", shape_doc(R"({"type": "triangle", "points": []})"), "shapes[1].type",
       "\"triangle\""},
      {"MissingShapeType", shape_doc(R"({"center": [1, 1], "radius": 1})"), "shapes[1].type",
       "missing"},
      {"ShapeNotObject", shape_doc("[1, 2]"), "shapes[1]", "object"},
      {"ShapesNotArray", scene_doc(R"(, "shapes": {})"), "shapes", "array"},
      // Ranges apply to the number as written, not to its float rounding.
      {"OpacityJustAboveOne",
       shape_doc(R"({"type": "box", "center": [1, 1], "size": [1, 1], "opacity": 1.00000001})"),
       "shapes[1].opacity", "found 1.00000001"},
      {"RadiusRoundingToZero",
       shape_doc(R"({"type": "circle", "center": [1, 1], "radius": 1e-50})"), "shapes[1].radius",
       "found 1e-50"},
      {"MissingRadius", shape_doc(R"({"type": "circle", "center": [1, 1]})"), "shapes[1].radius",
       "missing"},
      {"MissingCenter", shape_doc(R"({"type": "circle", "radius": 1})"), "shapes[1].center",
       "missing"},
      {"RadiusZero", shape_doc(R"({"type": "circle", "center": [1, 1], "radius": 0})"),
       "shapes[1].radius", "found 0"},
      {"RadiusNegative", shape_doc(R"({"type": "circle", "center": [1, 1], "radius": -2})"),
       "shapes[1].radius", "expected a number > 0, found -2"},
      {"BoxSizeZero", shape_doc(R"({"type": "box", "center": [1, 1], "size": [3, 0]})"),
       "shapes[1].size[1]", "found 0"},
      {"BoxSizeOneNumber", shape_doc(R"({"type": "box", "center": [1, 1], "size": [3]})"),
       "shapes[1].size", "pair"},
      {"BoxMissingSize", shape_doc(R"({"type": "box", "center": [1, 1]})"), "shapes[1].size",
       "missing"},
      {"BoxAngleString",
       shape_doc(R"({"type": "box", "center": [1, 1], "size": [1, 1], "angle": "90"})"),
       "shapes[1].angle", "string"},
      {"SegmentWidthZero",
       shape_doc(R"({"type": "segment", "a": [0, 0], "b": [1, 1], "width": 0})"), "shapes[1].width",
       "found 0"},
      {"SegmentMissingB", shape_doc(R"({"type": "segment", "a": [0, 0], "width": 1})"),
       "shapes[1].b", "missing"},
      {"OpacityAboveOne",
       shape_doc(R"({"type": "circle", "center": [1, 1], "radius": 1, "opacity": 1.5})"),
       "shapes[1].opacity", "found 1.5"},
      {"OpacityNegative",
       shape_doc(R"({"type": "circle", "center": [1, 1], "radius": 1, "opacity": -0.1})"),
       "shapes[1].opacity", "found -0.1"},
      {"AlbedoAboveOne",
       shape_doc(R"({"type": "circle", "center": [1, 1], "radius": 1, "albedo": [0.5, 1.2, 0]})"),
       "shapes[1].albedo[1]", "found 1.2"},
      {"EmissionNegative",
       shape_doc(R"({"type": "circle", "center": [1, 1], "radius": 1, "emission": [0, 0, -1]})"),
       "shapes[1].emission[2]", "found -1"},
      {"EmissionNotRgb",
       shape_doc(R"({"type": "circle", "center": [1, 1], "radius": 1, "emission": 3})"),
       "shapes[1].emission", "3 numbers"},
      {"PolygonTwoPoints", shape_doc(R"({"type": "polygon", "points": [[0, 0], [1, 1]]})"),
       "shapes[1].points", "at least 3"},
      {"PolygonMalformedPoint",
       shape_doc(R"({"type": "polygon", "points": [[0, 0], [1, 1, 2], [0, 1]]})"),
       "shapes[1].points[1]", "[x, y]"},
      {"PolygonPointNotNumber",
       shape_doc(R"({"type": "polygon", "points": [[0, 0], [1, 1], [0, null]]})"),
       "shapes[1].points[2][1]", "null"},
      {"CenterMalformed", shape_doc(R"({"type": "circle", "center": [1], "radius": 1})"),
       "shapes[1].center", "[x, y]"},
      {"UnknownShapeKey",
       shape_doc(R"({"type": "circle", "center": [1, 1], "radius": 1, "radus": 2})"),
       "shapes[1].radus", "unknown key \"radus\""},
      {"UnknownTopKey", scene_doc(R"(, "shape": [])"), "shape", "unknown key"},
      {"UnknownLayerKey", scene_doc(R"(, "layers": {"emision": "e.png"})"), "layers.emision",
       "unknown key"},
      {"LayerNotString", scene_doc(R"(, "layers": {"opacity": 1})"), "layers.opacity", "1"},
      {"EmissionScaleNegative", scene_doc(R"(, "layers": {"emission_scale": -1})"),
       "layers.emission_scale", "found -1"},
      {"Infinity", shape_doc(R"({"type": "circle", "center": [1e999, 1], "radius": 1})"),
       "shapes[1].center[0]", "finite"},
      {"TooLargeForFloat", shape_doc(R"({"type": "circle", "center": [1, 1], "radius": 1e300})"),
       "shapes[1].radius", "finite"},
      {"NegativeInfinity", scene_doc(R"(, "environment": [0, -1e999, 0])"), "environment[1]",
       "finite"},
  };
}

class SceneErrors : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(SceneErrors, NamesFileAndPath) {
  const ErrorCase& c = GetParam();
  auto r = parse_scene(c.json, "scene.json");
  penumbra::testing::expect_refused(r.ok(), r.ok() ? "" : r.error().message, c);
}

INSTANTIATE_TEST_SUITE_P(Scene, SceneErrors, ::testing::ValuesIn(error_cases()),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(Scene, SyntaxErrorNamesLineAndColumn) {
  auto r = parse_scene("{\n  \"penumbra\": 1,\n  \"width\": 4,,\n}", "scene.json");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message.rfind("scene.json: line 3, column 14: ", 0), 0u) << r.error().message;
  auto eof = parse_scene("{\"penumbra\": 1,\n", "x.json");
  ASSERT_FALSE(eof.ok());
  EXPECT_NE(eof.error().message.find("x.json: line 2, column 1"), std::string::npos)
      << eof.error().message;
}

TEST(Scene, MissingFileNamesPath) {
  TempDir dir;
  const std::string path = dir.file("nope.json");
  auto r = load_scene(path);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find(path), std::string::npos) << r.error().message;
}

TEST(Scene, LoadSceneReadsFile) {
  TempDir dir;
  auto r = load_scene(dir.write("s.json", kExample));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->shapes.size(), 4u);
  EXPECT_EQ(r->source, dir.file("s.json"));
}

// ---- validate() on scenes built in code. ----

TEST(Scene, ValidateChecksCodeScenes) {
  SceneDesc d;
  d.width = 8;
  d.height = 8;
  d.source = "my scene";
  d.shapes.push_back({Circle{{2, 2}, 1}, {}});
  EXPECT_TRUE(validate(d).ok());

  d.shapes.push_back({Circle{{2, 2}, -2}, {}});
  Status st = validate(d);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().message, "my scene: shapes[1].radius: expected a number > 0, found -2");

  d.shapes.back() = {Polygon{{{0, 0}, {1, std::numeric_limits<float>::quiet_NaN()}, {1, 0}}}, {}};
  st = validate(d);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().message.rfind("my scene: shapes[1].points[1][1]: ", 0), 0u)
      << st.error().message;

  d.shapes.pop_back();
  d.width = 16385;
  st = validate(d);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().message.rfind("my scene: width: ", 0), 0u) << st.error().message;

  d.width = 8;
  d.layers.opacity = std::vector<float>(64, 0.5f);
  (*d.layers.opacity)[8 * 3 + 5] = 1.5f;
  st = validate(d);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("layers.opacity"), std::string::npos);
  EXPECT_NE(st.error().message.find("(5, 3)"), std::string::npos) << st.error().message;

  d.layers.opacity.reset();
  d.layers.emission = ImageRgb(8, 7);
  st = validate(d);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("expected an image of 8x8"), std::string::npos)
      << st.error().message;
}

// ---- Layers. ----

TEST(Scene, PngEmissionLayerIsSrgbDecodedAndScaled) {
  TempDir dir;
  // 4x2 RGB, 8-bit; distinct values per pixel and channel.
  std::vector<unsigned char> px(4 * 2 * 3);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = static_cast<unsigned char>(i * 11);
  ASSERT_NE(stbi_write_png(dir.file("e.png").c_str(), 4, 2, 3, px.data(), 4 * 3), 0);
  auto r = load_scene(dir.write(
      "scene.json", scene_doc(R"(, "layers": {"emission": "e.png", "emission_scale": 2.5})")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_TRUE(r->layers.emission.has_value());
  const ImageRgb& e = *r->layers.emission;
  ASSERT_EQ(e.width(), 4);
  ASSERT_EQ(e.height(), 2);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 4; ++x) {
      Rgb v = e.at(x, y);
      const unsigned char* p = &px[(y * 4 + x) * 3];
      EXPECT_NEAR(v.r, 2.5 * srgb_decode(p[0] / 255.0), 1e-4);
      EXPECT_NEAR(v.g, 2.5 * srgb_decode(p[1] / 255.0), 1e-4);
      EXPECT_NEAR(v.b, 2.5 * srgb_decode(p[2] / 255.0), 1e-4);
    }
  }
}

TEST(Scene, GreyPngAlbedoIsExpandedAndDecoded) {
  TempDir dir;
  std::vector<unsigned char> px = {0, 64, 128, 255, 10, 20, 30, 200};
  ASSERT_NE(stbi_write_png(dir.file("a.png").c_str(), 4, 2, 1, px.data(), 4), 0);
  auto r = load_scene(dir.write("scene.json", scene_doc(R"(, "layers": {"albedo": "a.png"})")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  Rgb v = r->layers.albedo->at(2, 0);
  EXPECT_NEAR(v.r, srgb_decode(128 / 255.0), 1e-4);
  EXPECT_FLOAT_EQ(v.r, v.g);
  EXPECT_FLOAT_EQ(v.r, v.b);
}

TEST(Scene, PfmEmissionLayerIsLinear) {
  TempDir dir;
  std::vector<float> rgb(4 * 2 * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = 0.25f * float(i);
  // The layer path is relative to the scene file, which lives in the same directory.
  fs::create_directories(dir.file("sub"));
  write_pfm(dir.file("sub/e.pfm"), 4, 2, rgb);
  auto r = load_scene(dir.write(
      "sub/scene.json", scene_doc(R"(, "layers": {"emission": "e.pfm", "emission_scale": 3})")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  const ImageRgb& e = *r->layers.emission;
  EXPECT_FLOAT_EQ(e.at(0, 0).r, 0.0f);
  EXPECT_FLOAT_EQ(e.at(1, 0).g, 3 * 0.25f * 4);   // top row, x = 1, channel 1: index 4
  EXPECT_FLOAT_EQ(e.at(3, 1).b, 3 * 0.25f * 23);  // bottom row, last value
}

TEST(Scene, OpacityLayerReadsFirstChannel) {
  TempDir dir;
  std::vector<float> rgb;
  for (int i = 0; i < 8; ++i) {
    rgb.push_back(0.1f * float(i));  // first channel: the opacity
    rgb.push_back(0.9f);
    rgb.push_back(0.05f);
  }
  write_pfm(dir.file("o.pfm"), 4, 2, rgb);
  auto r = load_scene(dir.write("scene.json", scene_doc(R"(, "layers": {"opacity": "o.pfm"})")));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->layers.opacity->size(), 8u);
  for (int i = 0; i < 8; ++i) EXPECT_FLOAT_EQ((*r->layers.opacity)[i], 0.1f * float(i));
}

// Loads a scene whose layers are `layers_json` and expects it refused with a message that
// starts with the file and `layers.<layer>: ` and contains each of `words`.
void expect_layer_error(const TempDir& dir, const std::string& layers_json,
                        const std::string& layer, const std::vector<std::string>& words) {
  const std::string path =
      dir.write("scene_" + layer + ".json", scene_doc(", \"layers\": " + layers_json));
  auto r = load_scene(path);
  ASSERT_FALSE(r.ok());
  const std::string& m = r.error().message;
  EXPECT_EQ(m.rfind(path + ": layers." + layer + ": ", 0), 0u) << m;
  for (const std::string& w : words) EXPECT_NE(m.find(w), std::string::npos) << w << ": " << m;
}

TEST(Scene, LayerOfWrongSize) {
  TempDir dir;
  write_pfm(dir.file("e.pfm"), 3, 3, std::vector<float>(27, 1.0f));
  expect_layer_error(dir, R"({"emission": "e.pfm"})", "emission", {"4x2", "3x3"});
}

TEST(Scene, MissingLayerFile) {
  TempDir dir;
  expect_layer_error(dir, R"({"opacity": "missing.png"})", "opacity", {"missing.png"});
}

TEST(Scene, LayerWithNan) {
  TempDir dir;
  std::vector<float> rgb(24, 0.5f);
  rgb[(0 * 4 + 1) * 3 + 2] = std::numeric_limits<float>::quiet_NaN();  // pixel (1, 0), blue
  write_pfm(dir.file("e.pfm"), 4, 2, rgb);
  expect_layer_error(dir, R"({"emission": "e.pfm"})", "emission", {"(1, 0)"});
}

TEST(Scene, LayerWithNegativeOrInfiniteValue) {
  TempDir dir;
  std::vector<float> rgb(24, 0.5f);
  rgb[(1 * 4 + 3) * 3] = -1.0f;  // pixel (3, 1)
  write_pfm(dir.file("e.pfm"), 4, 2, rgb);
  expect_layer_error(dir, R"({"emission": "e.pfm"})", "emission", {"(3, 1)"});

  rgb[(1 * 4 + 3) * 3] = 0.5f;
  rgb[0] = std::numeric_limits<float>::infinity();
  write_pfm(dir.file("a.pfm"), 4, 2, rgb);
  expect_layer_error(dir, R"({"albedo": "a.pfm"})", "albedo", {"(0, 0)"});
}

}  // namespace
}  // namespace penumbra::flatland
