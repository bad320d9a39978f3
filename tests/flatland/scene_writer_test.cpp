// scene_json, the writer of the 2D format: what it writes reads back bit for bit, writing what
// was read gives the same text, and the example scenes are what it writes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "io/image_io.hpp"
#include "penumbra/flatland/scene.hpp"
#include "test_support.hpp"

namespace penumbra::flatland {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::slurp;

const fs::path kScenes = PENUMBRA_SOURCE_DIR "/scenes";

std::uint32_t bits(float v) {
  return std::bit_cast<std::uint32_t>(v);
}

// EXPECT_EQ on bits, so -0 and +0 differ; the float is printed too.
#define EXPECT_SAME_FLOAT(a, b, where) \
  EXPECT_EQ(bits(a), bits(b)) << (where) << ": " << (a) << " vs " << (b)

void expect_same(Rgb a, Rgb b, const std::string& where) {
  EXPECT_SAME_FLOAT(a.r, b.r, where + ".r");
  EXPECT_SAME_FLOAT(a.g, b.g, where + ".g");
  EXPECT_SAME_FLOAT(a.b, b.b, where + ".b");
}
void expect_same(std::array<float, 2> a, std::array<float, 2> b, const std::string& where) {
  EXPECT_SAME_FLOAT(a[0], b[0], where + "[0]");
  EXPECT_SAME_FLOAT(a[1], b[1], where + "[1]");
}

// Width, height, environment and shapes, every float bit for bit.
void expect_same(const SceneDesc& a, const SceneDesc& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  expect_same(a.environment, b.environment, "environment");
  ASSERT_EQ(a.shapes.size(), b.shapes.size());
  for (std::size_t i = 0; i < a.shapes.size(); ++i) {
    const std::string at = "shapes[" + std::to_string(i) + "]";
    const Shape &sa = a.shapes[i], &sb = b.shapes[i];
    ASSERT_EQ(sa.geometry.index(), sb.geometry.index()) << at;
    if (const auto* c = std::get_if<Circle>(&sa.geometry)) {
      const auto& d = std::get<Circle>(sb.geometry);
      expect_same(c->center, d.center, at + ".center");
      EXPECT_SAME_FLOAT(c->radius, d.radius, at + ".radius");
    } else if (const auto* x = std::get_if<Box>(&sa.geometry)) {
      const auto& y = std::get<Box>(sb.geometry);
      expect_same(x->center, y.center, at + ".center");
      expect_same(x->size, y.size, at + ".size");
      EXPECT_SAME_FLOAT(x->angle, y.angle, at + ".angle");
    } else if (const auto* g = std::get_if<Segment>(&sa.geometry)) {
      const auto& h = std::get<Segment>(sb.geometry);
      expect_same(g->a, h.a, at + ".a");
      expect_same(g->b, h.b, at + ".b");
      EXPECT_SAME_FLOAT(g->width, h.width, at + ".width");
    } else {
      const auto& p = std::get<Polygon>(sa.geometry).points;
      const auto& q = std::get<Polygon>(sb.geometry).points;
      ASSERT_EQ(p.size(), q.size()) << at;
      for (std::size_t k = 0; k < p.size(); ++k)
        expect_same(p[k], q[k], at + ".points[" + std::to_string(k) + "]");
    }
    expect_same(sa.material.emission, sb.material.emission, at + ".emission");
    EXPECT_SAME_FLOAT(sa.material.opacity, sb.material.opacity, at + ".opacity");
    expect_same(sa.material.albedo, sb.material.albedo, at + ".albedo");
  }
}

constexpr float kDenormMin = std::numeric_limits<float>::denorm_min();
constexpr float kMax = std::numeric_limits<float>::max();

// Every finite float whose bits a small generator gives, for points that cover the whole range.
std::vector<std::array<float, 2>> odd_points(int count) {
  std::vector<std::array<float, 2>> pts;
  std::uint32_t s = 0x9e3779b9u;
  auto next = [&] {
    for (;;) {
      s ^= s << 13;
      s ^= s >> 17;
      s ^= s << 5;
      const float v = std::bit_cast<float>(s);
      if (std::isfinite(v)) return v;
    }
  };
  while (int(pts.size()) < count) pts.push_back({next(), next()});
  return pts;
}

// Scenes built in code: every shape type and material combination, and awkward floats.
std::vector<SceneDesc> cases() {
  std::vector<SceneDesc> out;

  SceneDesc shapes;
  shapes.width = 64;
  shapes.height = 48;
  shapes.environment = {0.1f, 1e-7f, 3.4e38f};
  shapes.shapes = {
      {Circle{{10, 12}, 3}, {}},
      {Box{{20.5f, 8}, {4, 6}, 0}, {}},
      {Box{{30, 30}, {10, 2}, 33.3f}, {}},
      {Box{{30, 30}, {10, 2}, -0.0f}, {}},
      {Box{{30, 30}, {10, 2}, -720.125f}, {}},
      {Segment{{1, 2}, {40, 41}, 1.5f}, {}},
      {Polygon{{{0, 0}, {10, 0}, {10, 10}, {0, 10}, {5, 5}}}, {}},
  };
  out.push_back(shapes);

  SceneDesc materials;
  materials.width = 1;
  materials.height = 16384;
  auto disk = [](Material m) { return Shape{Circle{{0.5f, 0.5f}, 0.25f}, m}; };
  materials.shapes = {
      disk({{4, 3, 2}, 1, {}}),                    // emission only
      disk({{}, 0.1f, {}}),                        // opacity only
      disk({{}, 1, {0.8f, 0.5f, 0.2f}}),           // albedo only
      disk({{1e-7f, 0, kMax}, 0.5f, {1, 1, 1}}),   // all three
      disk({{}, 0, {}}),                           // clear
      disk({{}, kDenormMin, {kDenormMin, 0, 0}}),  // barely there
      disk({{-0.0f, 0, 0}, 1, {0, -0.0f, 0}}),     // -0 is not the default's +0
      disk({{0, 0, 1e-40f}, 0.99999994f, {}}),     // a denormal, the float below 1
      disk({{3.4e38f, 3.4e38f, 3.4e38f}, 1, {0.1f, 0.2f, 0.3f}}),
  };
  out.push_back(materials);

  SceneDesc odd;
  odd.width = 16384;
  odd.height = 1;
  odd.environment = {-0.0f, kDenormMin, 1e-40f};
  odd.shapes = {
      {Circle{{-0.0f, -3.4e38f}, kDenormMin}, {}},
      {Circle{{kMax, -kMax}, kMax}, {}},
      {Segment{{0.1f, -0.1f}, {1.0f / 3, 16777216.0f}, 1e-7f}, {}},
      {Box{{123456789.0f, -1e10f}, {1e-40f, 3.4e38f}, 1e-7f}, {}},
      // Its shortest text, read as a double and rounded to float, is the next float up.
      {Circle{{7.038531e-26f, -7.038531e-26f}, 7.038531e-26f}, {{7.038531e-26f, 0, 0}, 1, {}}},
      {Polygon{odd_points(500)}, {{1, 2, 3}, 0.25f, {0.5f, 0.5f, 0.5f}}},
  };
  out.push_back(odd);

  SceneDesc empty;  // no shapes at all
  empty.width = 7;
  empty.height = 9;
  out.push_back(empty);

  out.push_back(default_scene());
  return out;
}

// Fails on a number the format forbids: JSON has no NaN or infinity and the reader refuses
// what a float cannot hold.
void expect_finite_numbers(const json& j, const std::string& where) {
  if (j.is_number()) {
    const double d = j.get<double>();
    EXPECT_TRUE(std::isfinite(d) && std::isfinite(float(d))) << where << ": " << j.dump();
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i)
      expect_finite_numbers(j[i], where + "[" + std::to_string(i) + "]");
  } else if (j.is_object()) {
    for (const auto& [key, value] : j.items()) expect_finite_numbers(value, where + "." + key);
  }
}

TEST(SceneWriter, ReadsBackBitForBitAndWritesTheSameText) {
  for (const SceneDesc& d : cases()) {
    ASSERT_TRUE(validate(d).ok()) << validate(d).error().message;
    const std::string text = scene_json(d);
    Expected<SceneDesc> back = parse_scene(text, "written.json");
    ASSERT_TRUE(back.ok()) << back.error().message << "\n" << text;
    expect_same(d, *back);
    EXPECT_EQ(scene_json(*back), text);
  }
}

TEST(SceneWriter, WritesOnlyFiniteNumbers) {
  for (const SceneDesc& d : cases()) {
    ASSERT_TRUE(validate(d).ok()) << validate(d).error().message;  // the writer's precondition
    const std::string text = scene_json(d, {"e.png", "o.png", "a.png", kMax}, "d");
    json j;
    ASSERT_NO_THROW(j = json::parse(text)) << text;  // "nan" or "inf" would not parse
    expect_finite_numbers(j, "(document)");
  }
}

// Garbage in is refused on reading, never silently turned into a valid file.
TEST(SceneWriter, WhatValidateRefusesDoesNotReadBack) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<SceneDesc> bad;
  for (Shape s : {Shape{Circle{{nan, 0}, 1}, {}}, Shape{Circle{{0, 0}, inf}, {}},
                  Shape{Circle{{0, 0}, -2}, {}}, Shape{Circle{{0, 0}, 1}, {{}, 1.5f, {}}},
                  Shape{Polygon{{{0, 0}, {1, 1}}}, {}}}) {
    SceneDesc d;
    d.width = d.height = 8;
    d.shapes.push_back(s);
    bad.push_back(d);
  }
  SceneDesc zero;
  bad.push_back(zero);
  for (const SceneDesc& d : bad) {
    ASSERT_FALSE(validate(d).ok());
    const std::string text = scene_json(d);
    EXPECT_FALSE(parse_scene(text, "bad.json").ok()) << text;
  }
}

TEST(SceneWriter, LeavesOutDefaults) {
  SceneDesc d;
  d.width = d.height = 4;
  d.shapes.push_back({Box{{1, 1}, {1, 1}, 0}, {}});
  const std::string text = scene_json(d);
  for (const char* key : {"emission", "opacity", "albedo", "angle", "layers", "description"})
    EXPECT_EQ(text.find(key), std::string::npos) << key << " in\n" << text;
  EXPECT_EQ(text,
            "{\n  \"penumbra\": 1,\n  \"width\": 4,\n  \"height\": 4,\n  \"environment\": [0, 0, "
            "0],\n  \"shapes\": [\n    { \"type\": \"box\", \"center\": [1, 1], \"size\": [1, 1] "
            "}\n  ]\n}\n");
  // A layer file's default scale is left out; another scale is written.
  LayerFiles files;
  files.emission = "e.png";
  EXPECT_EQ(scene_json(d, files).find("emission_scale"), std::string::npos);
  EXPECT_NE(scene_json(d, {"e.png", "", "", 0.1f}).find("\"emission_scale\": 0.1"),
            std::string::npos);
}

TEST(SceneWriter, EscapesDescriptionAndLayerNames) {
  const std::string description = "A \"quoted\" scene\\with a backslash,\na newline, a\ttab, \x01";
  const LayerFiles files{R"(dir\"e".png)", R"(o\\.png)", "\"albedo\".png", 0.1f};
  SceneDesc d;
  d.width = d.height = 2;
  const std::string text = scene_json(d, files, description);
  json j;
  ASSERT_NO_THROW(j = json::parse(text)) << text;
  EXPECT_EQ(j["description"], description);
  EXPECT_EQ(j["layers"]["emission"], files.emission);
  EXPECT_EQ(j["layers"]["opacity"], files.opacity);
  EXPECT_EQ(j["layers"]["albedo"], files.albedo);
  EXPECT_EQ(bits(float(j["layers"]["emission_scale"].get<double>())), bits(0.1f));
}

// Layer names with quotes and backslashes name real files: the written scene loads them.
TEST(SceneWriter, OddLayerNamesLoadBack) {
  testing::TestDir dir("writer");
  const int w = 3, h = 2;
  std::vector<unsigned char> rgb(std::size_t(w) * h * 3);
  for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<unsigned char>(40 * i);
  const LayerFiles files{R"(e "quoted".png)", R"(o\back\slash.png)", R"(a\"both".png)", 0.1f};
  for (const std::string& name : {files.emission, files.opacity, files.albedo})
    ASSERT_TRUE(io::write_png8(dir.file(name), w, h, rgb).ok()) << name;

  SceneDesc d;
  d.width = w;
  d.height = h;
  d.shapes.push_back({Circle{{1, 1}, 0.5f}, {{1, 2, 3}, 0.5f, {}}});
  const std::string text = scene_json(d, files, "layers \"with\" odd names");
  const std::string path = dir.write("scene.json", text);
  Expected<SceneDesc> back = load_scene(path);
  ASSERT_TRUE(back.ok()) << back.error().message << "\n" << text;
  expect_same(d, *back);
  EXPECT_TRUE(back->layers.emission && back->layers.opacity && back->layers.albedo);
  EXPECT_EQ(bits(back->layers.emission_scale), bits(0.1f));
  EXPECT_EQ(scene_json(*back, files, "layers \"with\" odd names"), text);
}

// The layers a scene file names, as written in it.
LayerFiles layer_files(const json& doc) {
  LayerFiles f;
  if (!doc.contains("layers")) return f;
  const json& l = doc["layers"];
  if (l.contains("emission")) f.emission = l["emission"];
  if (l.contains("opacity")) f.opacity = l["opacity"];
  if (l.contains("albedo")) f.albedo = l["albedo"];
  if (l.contains("emission_scale")) f.emission_scale = float(l["emission_scale"].get<double>());
  return f;
}

// Every example scene reads back the same through the writer. The generated ones (written by
// penumbra_make_scenes, which calls scene_json) and occluder.json are exactly the writer's text;
// cornell, pinhole and room hold comment keys ("_note", "_layout") the writer does not keep.
TEST(SceneWriter, ExampleScenesRoundTrip) {
  const std::set<std::string> identical = {"lights_2", "lights_102", "lights_1002",
                                           "fog",      "painted",    "occluder"};
  int files = 0, compared = 0;
  for (const auto& entry : fs::directory_iterator(kScenes)) {
    if (entry.path().extension() != ".json") continue;
    ++files;
    const std::string name = entry.path().stem().string(), path = entry.path().string();
    const std::string committed = slurp(entry.path());
    const json doc = json::parse(committed);
    const std::string description = doc.value("description", "");
    const LayerFiles layers = layer_files(doc);

    Expected<SceneDesc> d = load_scene(path);
    ASSERT_TRUE(d.ok()) << d.error().message;
    const std::string text = scene_json(*d, layers, description);
    if (identical.count(name)) {
      ++compared;
      EXPECT_EQ(text, committed) << name;
    }
    // Parsed where the file is, so its layers load.
    Expected<SceneDesc> back = parse_scene(text, path);
    ASSERT_TRUE(back.ok()) << back.error().message;
    expect_same(*d, *back);
    EXPECT_EQ(scene_json(*back, layers, description), text) << name;
  }
  EXPECT_GE(files, 9);
  EXPECT_EQ(compared, int(identical.size()));
}

// fog.json names two layers: the written text names the same files and they load the same.
TEST(SceneWriter, LayeredSceneKeepsItsLayers) {
  const std::string path = (kScenes / "fog.json").string();
  const json doc = json::parse(slurp(path));
  const LayerFiles layers = layer_files(doc);
  EXPECT_EQ(layers.opacity, "layers/fog_opacity.png");
  EXPECT_EQ(layers.albedo, "layers/fog_albedo.png");
  Expected<SceneDesc> d = load_scene(path);
  ASSERT_TRUE(d.ok()) << d.error().message;

  const json written = json::parse(scene_json(*d, layers));
  EXPECT_EQ(written["layers"], doc["layers"]);
  Expected<SceneDesc> back = parse_scene(scene_json(*d, layers), path);
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_TRUE(back->layers.opacity && back->layers.albedo);
  EXPECT_FALSE(back->layers.emission);
  EXPECT_EQ(*back->layers.opacity, *d->layers.opacity);
  const ImageRgb &a = *back->layers.albedo, &b = *d->layers.albedo;
  ASSERT_EQ(a.size(), b.size());
  EXPECT_TRUE(std::equal(a.data(), a.data() + a.size(), b.data()));
}

}  // namespace
}  // namespace penumbra::flatland
