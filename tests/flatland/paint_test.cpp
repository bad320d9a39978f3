// The painter's canvas without a window: brush coverage, undo, saving and stroke files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "flatland/paint/canvas.hpp"
#include "penumbra/flatland/render.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using namespace penumbra;
using namespace penumbra::flatland;
using paint::Brush;
using paint::Canvas;
using paint::Stroke;
using paint::Tool;

Canvas blank(int w, int h, float scale = paint::kDefaultEmissionScale) {
  Expected<Canvas> c = Canvas::blank(w, h, scale);
  EXPECT_TRUE(c.ok()) << (c.ok() ? "" : c.error().message);
  return std::move(*c);
}

Brush brush(Tool tool, float radius, Rgb color = {1, 1, 1}, float intensity = 1) {
  Brush b;
  b.tool = tool;
  b.radius = radius;
  b.color = color;
  b.intensity = intensity;
  return b;
}

void paint_ok(Canvas& c, const Stroke& s) {
  Status st = c.apply(s);
  ASSERT_TRUE(st.ok()) << st.error().message;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

bool same_cells(const Scene& a, const Scene& b) {
  return a.width == b.width && a.height == b.height && same_bits(a.emission, b.emission) &&
         same_bits(a.opacity, b.opacity) && same_bits(a.albedo, b.albedo);
}

// The canvas holds only values a 16-bit layer decodes to: every code must survive decode then
// encode, at the scales the painter uses, or a saved painting would not read back exactly.
TEST(PaintCodes, EveryCodeSurvivesDecodeAndEncode) {
  for (int code = 0; code < 65536; ++code) {
    const auto c = std::uint16_t(code);
    ASSERT_EQ(paint::encode_linear16(paint::decode_linear16(c)), c);
    ASSERT_EQ(paint::encode_srgb16(paint::decode_srgb16(c)), c);
    for (float scale : {64.0f, 128.0f, 1024.0f})
      ASSERT_EQ(paint::encode_srgb16(paint::decode_srgb16(c) * scale / scale), c) << scale;
  }
}

TEST(PaintCanvas, LightStrokeCoversItsDiskWithTheBrushMaterial) {
  Canvas c = blank(32, 32);
  paint_ok(c, {brush(Tool::light, 4, {1, 0.5f, 0.25f}, 8), {{16.5f, 16.5f}}});
  const Scene& s = c.scene();
  const std::size_t centre = s.index(16, 16), outside = s.index(16, 24);
  EXPECT_EQ(s.opacity[centre], 1.0f);
  EXPECT_NEAR(s.emission[3 * centre + 0], 8.0f, 8e-3f);  // within the 16-bit step
  EXPECT_NEAR(s.emission[3 * centre + 1], 4.0f, 4e-3f);
  EXPECT_NEAR(s.emission[3 * centre + 2], 2.0f, 2e-3f);
  EXPECT_EQ(s.opacity[outside], 0.0f);
  EXPECT_EQ(s.emission[3 * outside], 0.0f);
  // The edge is anti-aliased as the rasteriser does it: a cell whose centre lies on the radius is
  // half covered, and an opaque material's edge blends by c^4, keeping its own radiance.
  const std::size_t edge = s.index(20, 16);  // centre at 20.5, 4 from the stroke
  EXPECT_NEAR(s.opacity[edge], 0.0625f, 1e-4f);
  EXPECT_NEAR(s.emission[3 * edge], 8.0f, 8e-3f);
}

// A fast mouse gives far-apart points: the segments between them are painted, no gaps.
TEST(PaintCanvas, StrokesInterpolateBetweenFarPoints) {
  Canvas c = blank(128, 32);
  paint_ok(c, {brush(Tool::wall, 1, {0.5f, 0.5f, 0.5f}), {{2, 10.5f}, {120, 10.5f}, {120, 30}}});
  const Scene& s = c.scene();
  for (int x = 2; x < 120; ++x) EXPECT_EQ(s.opacity[s.index(x, 10)], 1.0f) << "x " << x;
  for (int y = 11; y < 30; ++y) EXPECT_EQ(s.opacity[s.index(120, y)], 1.0f) << "y " << y;
  EXPECT_EQ(s.opacity[s.index(60, 20)], 0.0f);
}

// Points far off the grid paint what they reach and nothing else.
TEST(PaintCanvas, PointsFarOffTheGridAreSafe) {
  Canvas c = blank(16, 16);
  paint_ok(c, {brush(Tool::wall, 2), {{1e8f, 1e8f}, {-1e8f, -1e8f}}});
  const Scene& s = c.scene();
  EXPECT_EQ(s.opacity[s.index(0, 0)], 1.0f);  // the diagonal crosses the grid
  EXPECT_EQ(s.opacity[s.index(15, 15)], 1.0f);
  EXPECT_EQ(s.opacity[s.index(15, 0)], 0.0f);
  c.clear();
  // One end far off, the other on the grid: the line keeps its direction.
  for (float far : {1e8f, 1e20f, 1e30f}) {
    paint_ok(c, {brush(Tool::wall, 1), {{far, far}, {8, 8}}});
    for (int i = 8; i < 16; ++i) EXPECT_EQ(s.opacity[s.index(i, i)], 1.0f) << far << " " << i;
    EXPECT_EQ(s.opacity[s.index(15, 9)], 0.0f) << far;
    c.clear();
    paint_ok(c, {brush(Tool::wall, 1), {{8, 8}, {-far, far}}});
    for (int i = 0; i < 8; ++i) EXPECT_EQ(s.opacity[s.index(i, 15 - i)], 1.0f) << far << " " << i;
    c.clear();
  }
  // Points as far as a float goes: the line is not defined to a cell there, but painting them
  // is safe.
  paint_ok(c, {brush(Tool::wall, 2), {{3e38f, 3e38f}, {-3e38f, -3e38f}, {3e38f, -3e38f}}});
  c.clear();
  // A segment from far left to far right covers its whole row: clipping keeps the precision.
  for (float far : {100.0f, 1e8f, 1e20f, 3e38f}) {
    paint_ok(c, {brush(Tool::wall, 2), {{-far, 8.5f}, {far, 8.5f}}});
    for (int x = 0; x < 16; ++x) EXPECT_EQ(s.opacity[s.index(x, 8)], 1.0f) << far << " " << x;
    EXPECT_EQ(s.opacity[s.index(8, 0)], 0.0f) << far;
    c.clear();
  }
  // Wholly off the grid: nothing.
  paint_ok(c, {brush(Tool::wall, 2), {{-3e38f, -50}, {3e38f, -50}}});
  for (float o : s.opacity) ASSERT_EQ(o, 0.0f);
}

// Fog laid twice over the same cells by one stroke keeps the brush's opacity: a stroke covers a
// cell once (its largest coverage), so joints and back-and-forth motion do not thicken it.
TEST(PaintCanvas, OneStrokeCoversACellOnce) {
  Canvas c = blank(64, 64);
  Brush fog = brush(Tool::fog, 6, {0.3f, 0.3f, 0.3f});
  fog.opacity = 0.2f;
  paint_ok(c, {fog, {{10, 32}, {50, 32}, {10, 32}, {50, 33}}});
  const Scene& s = c.scene();
  EXPECT_NEAR(s.opacity[s.index(30, 32)], 0.2f, 1e-4f);
  for (int x = 12; x < 48; ++x) EXPECT_NEAR(s.opacity[s.index(x, 32)], 0.2f, 1e-4f);
  // A second stroke over the first blends with what was there: still at most the brush value.
  paint_ok(c, {fog, {{30, 32}}});
  EXPECT_NEAR(s.opacity[s.index(30, 32)], 0.2f, 1e-4f);
}

TEST(PaintCanvas, EraserClearsAndUndoRestoresEveryBit) {
  Canvas c = blank(48, 48);
  paint_ok(c, {brush(Tool::wall, 3, {0.8f, 0.6f, 0.4f}), {{10, 10}, {40, 40}}});
  const Scene walls = c.scene();
  paint_ok(c, {brush(Tool::erase, 30), {{24, 24}}});
  for (float o : c.scene().opacity) ASSERT_EQ(o, 0.0f);
  for (float a : c.scene().albedo) ASSERT_EQ(a, 0.0f);
  EXPECT_EQ(c.undo_steps(), 2u);
  ASSERT_TRUE(c.undo());
  EXPECT_TRUE(same_cells(c.scene(), walls));
  c.clear();
  for (float o : c.scene().opacity) ASSERT_EQ(o, 0.0f);
  ASSERT_TRUE(c.undo());
  EXPECT_TRUE(same_cells(c.scene(), walls));
  ASSERT_TRUE(c.undo());
  for (float o : c.scene().opacity) ASSERT_EQ(o, 0.0f);
  EXPECT_FALSE(c.undo());
}

TEST(PaintCanvas, VersionMovesOnEveryEdit) {
  Canvas c = blank(16, 16);
  const auto v0 = c.version();
  ASSERT_TRUE(c.begin_stroke(brush(Tool::light, 2), 4, 4).ok());
  const auto v1 = c.version();
  c.extend_stroke(8, 8);
  const auto v2 = c.version();
  c.end_stroke();
  c.set_environment({0.1f, 0.1f, 0.1f});
  const auto v3 = c.version();
  EXPECT_LT(v0, v1);
  EXPECT_LT(v1, v2);
  EXPECT_LT(v2, v3);
  // A new canvas (a scene loaded in place of this one) never repeats a version, or the solver
  // would not render it.
  Canvas d = blank(16, 16);
  EXPECT_NE(d.version(), v0);
  EXPECT_GT(d.version(), v3);
}

TEST(PaintCanvas, RefusesBrushesItCannotHold) {
  Canvas c = blank(16, 16, 64);
  Status s = c.apply({brush(Tool::light, 2, {1, 1, 1}, 100), {{4, 4}}}, "strokes[2]");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("strokes[2].intensity"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("64"), std::string::npos) << s.error().message;
  Brush fog = brush(Tool::fog, 2);
  fog.opacity = 1;
  s = c.apply({fog, {{4, 4}}});
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("stroke.opacity"), std::string::npos) << s.error().message;
  s = c.apply({brush(Tool::wall, 0.1f), {{4, 4}}});
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("stroke.radius"), std::string::npos) << s.error().message;
  s = c.apply({brush(Tool::wall, 2), {}});
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("stroke.points"), std::string::npos) << s.error().message;
  for (float o : c.scene().opacity) ASSERT_EQ(o, 0.0f);  // nothing was painted
  EXPECT_FALSE(Canvas::blank(0, 16).ok());
  EXPECT_FALSE(Canvas::blank(paint::kMaxCanvasSide + 1, 16).ok());
}

// A painted light lights its surroundings; a painted wall casts a shadow.
TEST(PaintCanvas, PaintedLightAndWallRenderLightAndShadow) {
  Canvas c = blank(96, 96);
  paint_ok(c, {brush(Tool::light, 4, {1, 1, 1}, 4), {{30, 48}}});
  paint_ok(c, {brush(Tool::wall, 1.5f, {0.5f, 0.5f, 0.5f}), {{48, 20}, {48, 76}}});
  RenderOptions o;
  o.method = Method::hrc;
  const RenderResult r = penumbra::testing::render_valid(c.scene(), o);
  auto f = [&](int x, int y) { return r.fluence.data()[3 * c.scene().index(x, y)]; };
  const float near = f(38, 48), front = f(22, 48), behind = f(66, 48);
  EXPECT_GT(near, 10 * behind);
  EXPECT_GT(front, 10 * behind);  // same distance from the light, other side
  // The painted disk is the scene format's circle of the same radius: the fluence it gives
  // matches the rasterised shape's (the closed form is the rasteriser's test).
  SceneDesc d;
  d.width = d.height = 96;
  d.shapes.push_back({Circle{{30, 48}, 4}, Material{{4, 4, 4}, 1, {}}});
  const RenderResult shape = penumbra::testing::render_valid(penumbra::testing::build_valid(d), o);
  for (int x : {22, 14, 4}) {
    const float want = shape.fluence.data()[3 * c.scene().index(x, 48)];
    EXPECT_NEAR(f(x, 48), want, 0.03f * want) << "x " << x;
  }
}

// Saving writes a scene file that reads back to the very same cells, so `penumbra render`
// gives what the painter showed.
TEST(PaintCanvas, SavedPaintingReadsBackBitForBit) {
  penumbra::testing::TestDir dir("paint");
  Canvas c = blank(64, 40, 32);
  c.set_environment({0.02f, 0.03f, 0.05f});
  paint_ok(c, {brush(Tool::light, 3.3f, {1, 0.7f, 0.2f}, 17.3f), {{12.3f, 20.1f}, {14, 30}}});
  paint_ok(c, {brush(Tool::wall, 2.2f, {0.8f, 0.1f, 0.3f}), {{32, 3}, {30, 37}}});
  Brush fog = brush(Tool::fog, 7, {0.4f, 0.5f, 0.6f});
  fog.opacity = 0.07f;
  paint_ok(c, {fog, {{50, 10}, {55, 30}}});
  paint_ok(c, {brush(Tool::erase, 1.7f), {{31, 20}, {33, 22}}});
  const std::string path = dir.file("painting.json");
  Status s = c.save(path);
  ASSERT_TRUE(s.ok()) << s.error().message;
  for (const char* f : {"painting.emission.png", "painting.opacity.png", "painting.albedo.png"})
    EXPECT_TRUE(fs::exists(dir.root() / f)) << f;

  Expected<SceneDesc> desc = load_scene(path);
  ASSERT_TRUE(desc.ok()) << desc.error().message;
  const Scene back = penumbra::testing::build_valid(*desc);
  EXPECT_TRUE(same_cells(back, c.scene()));
  EXPECT_EQ(back.environment.r, c.scene().environment.r);
  EXPECT_EQ(back.environment.b, c.scene().environment.b);

  RenderOptions o;
  o.method = Method::hrc;
  o.bounces = 2;
  const RenderResult a = penumbra::testing::render_valid(c.scene(), o);
  const RenderResult b = penumbra::testing::render_valid(back, o);
  ASSERT_EQ(a.fluence.width(), b.fluence.width());
  EXPECT_EQ(std::memcmp(a.fluence.data(), b.fluence.data(),
                        std::size_t(a.fluence.width()) * a.fluence.height() * 3 * sizeof(float)),
            0);

  // A loaded painting is already on the 16-bit codes: loading it as a canvas changes nothing.
  Expected<Canvas> again = Canvas::from_scene(*desc);
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_TRUE(same_cells(again->scene(), c.scene()));
  EXPECT_EQ(again->emission_scale(), 32.0f);  // the file's
  // Asking for more room to paint brighter lights rescales it.
  Expected<Canvas> roomier = Canvas::from_scene(*desc, 100);
  ASSERT_TRUE(roomier.ok()) << roomier.error().message;
  EXPECT_EQ(roomier->emission_scale(), 100.0f);
}

TEST(PaintCanvas, SaveIsAllOrNothing) {
  penumbra::testing::TestDir dir("paint");
  Canvas c = blank(8, 8);
  Status s = c.save(dir.file("missing/painting.json"));
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("missing"), std::string::npos) << s.error().message;
  s = c.save(dir.file("painting.png"));
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find(".json"), std::string::npos) << s.error().message;
  // The JSON can be written but a layer cannot (a directory is in its place).
  fs::create_directories(dir.root() / "painting.albedo.png");
  s = c.save(dir.file("painting.json"));
  ASSERT_FALSE(s.ok());
  std::vector<std::string> left = dir.entries();
  EXPECT_EQ(left.size(), 1u) << ::testing::PrintToString(left);
}

// A scene file becomes a canvas of its rasterised cells, each moved to the nearest 16-bit code.
TEST(PaintCanvas, SceneFileBecomesCanvasWithinOneCode) {
  SceneDesc d;
  d.width = 40;
  d.height = 30;
  d.environment = {0.1f, 0.2f, 0.3f};
  d.shapes.push_back({Circle{{10, 15}, 4}, Material{{200, 100, 3}, 1, {}}});
  d.shapes.push_back({Box{{28, 15}, {3, 20}, 20}, Material{{}, 1, {0.7f, 0.5f, 0.3f}}});
  d.shapes.push_back({Circle{{30, 5}, 6}, Material{{}, 0.3f, {0.2f, 0.2f, 0.2f}}});
  const Scene built = penumbra::testing::build_valid(d);
  Expected<Canvas> c = Canvas::from_scene(d);
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_EQ(c->emission_scale(), 256.0f);
  const Scene& s = c->scene();
  EXPECT_EQ(s.environment.g, 0.2f);
  for (std::size_t i = 0; i < s.cells(); ++i) {
    ASSERT_NEAR(s.opacity[i], built.opacity[i], 0.5f / 65535) << i;
    for (int k = 0; k < 3; ++k) {
      // One sRGB code is at most 1/65535 / 0.41 of the value (the curve's least slope, at 1).
      ASSERT_NEAR(s.emission[3 * i + k], built.emission[3 * i + k], 256.0f * 4e-5f) << i;
      ASSERT_NEAR(s.albedo[3 * i + k], built.albedo[3 * i + k], 4e-5f) << i;
    }
  }
  SceneDesc huge;
  huge.width = paint::kMaxCanvasSide + 1;
  huge.height = 4;
  huge.source = "huge.json";
  Expected<Canvas> h = Canvas::from_scene(huge);
  ASSERT_FALSE(h.ok());
  EXPECT_NE(h.error().message.find("huge.json"), std::string::npos) << h.error().message;
}

// ---- stroke files ----------------------------------------------------------------------------

TEST(PaintStrokes, ParseAndWriteRoundTrip) {
  Expected<paint::StrokeFile> f = paint::parse_strokes(R"({"size": [64, 32], "strokes": [
    {"tool": "light", "color": [1, 0.5, 0], "intensity": 6, "radius": 4, "points": [[1, 2], [3.5, 4]]},
    {"tool": "wall", "color": [0.5, 0.5, 0.5], "radius": 2, "points": [[10, 0]]},
    {"tool": "fog", "opacity": 0.3, "points": [[5, 5]]},
    {"tool": "erase", "radius": 8, "points": [[0, 0], [9, 9]]},
    {"tool": "eraser", "points": [[1, 1]]}]})",
                                                       "s.json");
  ASSERT_TRUE(f.ok()) << f.error().message;
  const std::vector<Stroke>& s = f->strokes;
  ASSERT_EQ(s.size(), 5u);
  EXPECT_EQ(f->width, 64);
  EXPECT_EQ(f->height, 32);
  EXPECT_EQ(s[0].brush.tool, Tool::light);
  EXPECT_EQ(s[0].brush.intensity, 6.0f);
  EXPECT_EQ(s[0].points[1][0], 3.5f);
  EXPECT_EQ(s[2].brush.opacity, 0.3f);
  EXPECT_EQ(s[2].brush.radius, Brush{}.radius);  // default
  EXPECT_EQ(s[3].brush.tool, Tool::erase);
  EXPECT_EQ(s[4].brush.tool, Tool::erase);  // "eraser", as the window calls it

  Expected<paint::StrokeFile> back = paint::parse_strokes(paint::strokes_json(*f), "back.json");
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->strokes.size(), s.size());
  EXPECT_EQ(back->width, 64);
  EXPECT_EQ(back->height, 32);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const Brush &a = s[i].brush, &b = back->strokes[i].brush;
    EXPECT_EQ(a.tool, b.tool);
    EXPECT_EQ(a.radius, b.radius);
    EXPECT_EQ(a.color.g, b.color.g);
    EXPECT_EQ(a.intensity, b.intensity);
    EXPECT_EQ(a.opacity, b.opacity);
    EXPECT_EQ(s[i].points, back->strokes[i].points);
  }
}

TEST(PaintStrokes, ErrorsNameTheFileAndJsonPath) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"strokes": [{"points": [[1, 1]]}]})", "strokes[0].tool"},
      {R"({"strokes": [{"tool": "spray", "points": [[1, 1]]}]})", "strokes[0].tool"},
      {R"({"strokes": [{"tool": "wall", "radius": -1, "points": [[1, 1]]}]})", "strokes[0].radius"},
      {R"({"strokes": [{"tool": "wall", "points": []}]})", "strokes[0].points"},
      {R"({"strokes": [{"tool": "wall"}]})", "strokes[0].points"},
      {R"({"strokes": [{"tool": "wall", "points": [[1, 1], [2]]}]})", "strokes[0].points[1]"},
      {R"({"strokes": [{"tool": "wall", "points": [[1, "a"]]}]})", "strokes[0].points[0][1]"},
      {R"({"strokes": [{"tool": "wall", "color": [1, 2, 0], "points": [[1, 1]]}]})",
       "strokes[0].color[1]"},
      {R"({"strokes": [{"tool": "fog", "opacity": 1, "points": [[1, 1]]}]})", "strokes[0].opacity"},
      {R"({"strokes": [{"tool": "light", "intensity": -2, "points": [[1, 1]]}]})",
       "strokes[0].intensity"},
      {R"({"strokes": [{}, {"tool": "wall", "size": 3, "points": [[1, 1]]}]})", "strokes[0].tool"},
      {R"({"strokes": [{"tool": "wall", "size": 3, "points": [[1, 1]]}]})", "strokes[0].size"},
      {R"({"strokes": 3})", "strokes"},
      {R"({"lines": []})", "lines"},
      {R"({"strokes": [)", "line 1, column 14: invalid JSON"},
      {R"({"strokes": [{"tool": "wall", "radius": 1e999, "points": [[1, 1]]}]})",
       "strokes[0].radius: expected a finite number, found 1e999 (out of range)"},
      {R"({"size": [0, 4], "strokes": []})", "size"},
      {R"({"size": [4], "strokes": []})", "size"},
      {R"({"size": [4.5, 4], "strokes": []})", "size"},
  };
  for (const auto& [text, path] : cases) {
    Expected<paint::StrokeFile> s = paint::parse_strokes(text, "bad.json");
    ASSERT_FALSE(s.ok()) << text;
    EXPECT_EQ(s.error().message.rfind("bad.json: ", 0), 0u) << s.error().message;
    EXPECT_NE(s.error().message.find(path), std::string::npos) << s.error().message;
  }
  Expected<paint::StrokeFile> missing = paint::load_strokes("/nonexistent/strokes.json");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("/nonexistent/strokes.json"), std::string::npos);
}

// The stroke files shipped in scenes/strokes paint without error on the canvas they are made for.
TEST(PaintStrokes, ExampleStrokeFilesPaint) {
  int files = 0;
  for (const auto& e : fs::directory_iterator(fs::path(PENUMBRA_SOURCE_DIR) / "scenes/strokes")) {
    Expected<paint::StrokeFile> s = paint::load_strokes(e.path().string());
    ASSERT_TRUE(s.ok()) << s.error().message;
    Canvas c = blank(256, 256);
    for (std::size_t i = 0; i < s->strokes.size(); ++i) {
      Status st = c.apply(s->strokes[i], "strokes[" + std::to_string(i) + "]");
      EXPECT_TRUE(st.ok()) << e.path() << ": " << st.error().message;
    }
    EXPECT_EQ(c.undo_steps(), s->strokes.size());
    ++files;
  }
  EXPECT_GE(files, 1);
}

}  // namespace
