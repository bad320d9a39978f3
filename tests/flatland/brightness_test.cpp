// Scenes at the edge of the float range: a scene whose fluence a float cannot hold is refused,
// naming its brightest value; a scene too bright for a method's storage is rendered at a
// power-of-two fraction of its light and scaled back exactly; nothing that is not finite is ever
// returned.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "io/json_reader.hpp"
#include "penumbra/flatland/render.hpp"
#include "penumbra/flatland/scene.hpp"
#include "test_support.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::flatland;

// A light, an occluder that bounces light, and an environment, all scaled by `light`.
SceneDesc lit_desc(float light) {
  SceneDesc d;
  d.width = d.height = 32;
  d.source = "bright.json";
  d.environment = {0.25f * light, 0.5f * light, 0.125f * light};
  d.shapes.push_back({Circle{{10, 16}, 3}, Material{{4 * light, 2 * light, light}, 1, {}}});
  d.shapes.push_back({Box{{22, 16}, {3, 12}, 0}, Material{{}, 1, {0.5f, 0.75f, 0.25f}}});
  return d;
}

std::vector<RenderOptions> every_method(int bounces) {
  std::vector<RenderOptions> list(4);
  list[0].method = Method::rc;
  list[1].method = Method::hrc;
  list[2].method = Method::hrc;
  list[2].hrc.storage = Storage::f16;
  list[3] = penumbra::testing::pt_options(2, Sampler::r1, true);
  for (RenderOptions& o : list) {
    o.bounces = bounces;
    o.threads = 1;
  }
  return list;
}

std::string label(const RenderOptions& o) {
  return std::string(to_string(o.method)) + (o.hrc.storage == Storage::f16 ? " f16" : "");
}

// Every method is linear in the light, and powers of two only move exponents: a scene 2^k times
// brighter renders to exactly 2^k times the fluence, whether or not the dispatcher scaled it
// (2^70 passes the float storage's 2^64, 2^20 passes HRC f16's 41,700).
TEST(Brightness, PowerOfTwoBrighterScenesRenderExactlyScaled) {
  const Scene unit = penumbra::testing::build_valid(lit_desc(1));
  for (int k : {20, 70, 118}) {
    const Scene bright = penumbra::testing::build_valid(lit_desc(std::ldexp(1.0f, k)));
    for (const RenderOptions& o : every_method(2)) {
      const RenderResult a = penumbra::testing::render_valid(unit, o);
      Expected<RenderResult> b = render(bright, o);
      ASSERT_TRUE(b.ok()) << label(o) << " 2^" << k << ": " << b.error().message;
      const std::size_t n = unit.cells() * 3;
      std::size_t differ = 0;
      for (std::size_t i = 0; i < n; ++i)
        differ += std::ldexp(a.fluence.data()[i], k) != b->fluence.data()[i];
      EXPECT_EQ(differ, 0u) << label(o) << " 2^" << k;
    }
  }
}

// Not a power of two: the light 1e30 renders to 1e30 times the unit light's fluence, within the
// rounding of the scaled inputs.
TEST(Brightness, BrightScenesStayFiniteAndProportional) {
  const Scene unit = penumbra::testing::build_valid(lit_desc(1));
  const Scene bright = penumbra::testing::build_valid(lit_desc(1e30f));
  for (const RenderOptions& o : every_method(1)) {
    const RenderResult a = penumbra::testing::render_valid(unit, o);
    Expected<RenderResult> b = render(bright, o);
    ASSERT_TRUE(b.ok()) << label(o) << ": " << b.error().message;
    double worst = 0;
    for (std::size_t i = 0; i < unit.cells() * 3; ++i) {
      const double want = double(a.fluence.data()[i]) * 1e30;
      worst = std::max(worst, std::fabs(b->fluence.data()[i] - want) / (want + 1e24));
    }
    EXPECT_LT(worst, o.hrc.storage == Storage::f16 ? 2e-3 : 1e-5) << label(o);
  }
}

// Emission 3e38 is finite, so the format allows it, but the fluence it gives is not: every method
// used to return infinities or NaN. Refused, naming the value.
TEST(Brightness, SceneBeyondTheFloatRangeIsRefusedNamingTheValue) {
  SceneDesc d = lit_desc(1);
  d.shapes[0].material.emission = {3e38f, 0, 0};
  const Scene scene = penumbra::testing::build_valid(d);
  for (const RenderOptions& o : every_method(1)) {
    Status desc_check = check_brightness(d, o);
    ASSERT_FALSE(desc_check.ok()) << label(o);
    EXPECT_EQ(desc_check.error().message.rfind("bright.json: shapes[0].emission: 3e+38 is too "
                                               "bright to render: the fluence can reach 2 pi x "
                                               "3e+38 x 1 bounce = 1.88e+39",
                                               0),
              0u)
        << desc_check.error().message;
    Expected<RenderResult> r = render(scene, o);
    ASSERT_FALSE(r.ok()) << label(o);
    EXPECT_NE(r.error().message.find("scene: the emission of cell ("), std::string::npos)
        << r.error().message;
    EXPECT_NE(r.error().message.find("too bright to render"), std::string::npos)
        << r.error().message;
  }
  // The environment alone.
  d = lit_desc(1);
  d.environment = {0, 3e38f, 0};
  EXPECT_NE(check_brightness(d, {}).error().message.find("bright.json: environment: 3e+38"),
            std::string::npos);
  Expected<RenderResult> r = render(penumbra::testing::build_valid(d), {});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("scene: the environment: 3e+38"), std::string::npos)
      << r.error().message;
  // An emission layer names its pixel.
  d = lit_desc(1);
  ImageRgb layer(32, 32);
  layer.data()[(5 * 32 + 7) * 3 + 2] = 1e38f;
  d.layers.emission = layer;
  EXPECT_NE(
      check_brightness(d, {}).error().message.find("layers.emission: pixel (7, 5): 1e+38 is too"),
      std::string::npos)
      << check_brightness(d, {}).error().message;
}

// The bound grows with the bounces: 5e37 fits one bounce (2 pi x 5e37 = 3.14e38, just below the
// largest float) but not two.
TEST(Brightness, TheBoundCountsBounces) {
  SceneDesc d = lit_desc(1);
  d.shapes[0].material.emission = {5e37f, 5e37f, 5e37f};
  RenderOptions o;
  EXPECT_TRUE(check_brightness(d, o).ok());
  Expected<RenderResult> r = render(penumbra::testing::build_valid(d), o);
  ASSERT_TRUE(r.ok()) << r.error().message;
  for (std::size_t i = 0; i < 32 * 32 * 3; ++i) ASSERT_TRUE(std::isfinite(r->fluence.data()[i]));
  o.bounces = 2;
  EXPECT_FALSE(check_brightness(d, o).ok());
  EXPECT_FALSE(render(penumbra::testing::build_valid(d), o).ok());
}

// A Scene built by hand can hold values the format refuses: they are reported, not rendered.
TEST(Brightness, ValuesThatAreNotFiniteAreRefused) {
  Scene s = penumbra::testing::build_valid(lit_desc(1));
  s.emission[(3 * 32 + 4) * 3 + 1] = std::numeric_limits<float>::quiet_NaN();
  for (const RenderOptions& o : every_method(1)) {
    Expected<RenderResult> r = render(s, o);
    ASSERT_FALSE(r.ok()) << label(o);
    EXPECT_EQ(r.error().message, "scene: the emission of cell (4, 3) is not finite");
  }
  s = penumbra::testing::build_valid(lit_desc(1));
  s.environment.g = std::numeric_limits<float>::infinity();
  Expected<RenderResult> r = render(s, {});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().message, "scene: the environment is not finite");
}

TEST(Brightness, NumbersReadAsAPersonWrites) {
  EXPECT_EQ(io::format_rounded(FLT_MAX), "3.4e+38");
  EXPECT_EQ(io::format_rounded(65504.0 / (3.14159265358979 / 2)), "41700");
  EXPECT_EQ(io::format_rounded(1e37), "1e+37");
  EXPECT_EQ(io::format_rounded(0.5), "0.5");
  EXPECT_EQ(io::format_rounded(123.456), "123");
}

}  // namespace
