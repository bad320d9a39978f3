// penumbra::flatland::Renderer: a renderer kept from frame to frame gives what a fresh render()
// gives, whatever it rendered before (other methods, options, grid sizes).
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "penumbra/flatland/render.hpp"
#include "test_support.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::flatland;

Scene scene(int w, int h, float x) {
  SceneDesc d;
  d.width = w;
  d.height = h;
  d.environment = {0.01f, 0.02f, 0.03f};
  d.shapes.push_back({Circle{{x, h / 2.0f}, 3}, Material{{4, 3, 2}, 1, {}}});
  d.shapes.push_back(
      {Box{{w / 2.0f, h / 2.0f}, {2, h / 2.0f}, 0}, Material{{}, 1, {0.5f, 0.5f, 0.5f}}});
  d.shapes.push_back({Circle{{w * 0.75f, h * 0.3f}, 6}, Material{{}, 0.2f, {0.3f, 0.3f, 0.3f}}});
  return penumbra::testing::build_valid(d);
}

TEST(Renderer, ReusedRendererMatchesFreshRenders) {
  RenderOptions rc, rc_plain, hrc, hrc_f16, pt;
  rc.method = Method::rc;
  rc_plain.method = Method::rc;
  rc_plain.distance_field = false;
  rc_plain.blocks = false;
  rc_plain.bounces = 2;
  hrc.method = Method::hrc;
  hrc.bounces = 2;
  hrc_f16.method = Method::hrc;
  hrc_f16.hrc.storage = Storage::f16;
  pt.method = Method::pt;
  pt.pt.spp = 4;
  const Scene a = scene(64, 48, 12), b = scene(40, 40, 30), c = scene(64, 48, 50);
  struct Step {
    const Scene* s;
    const RenderOptions* o;
  };
  const std::vector<Step> steps = {{&a, &rc},      {&a, &hrc},      {&b, &hrc},
                                   {&c, &hrc},     {&c, &rc_plain}, {&b, &rc},
                                   {&a, &hrc_f16}, {&a, &pt},       {&c, &hrc}};
  Renderer renderer;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    Expected<RenderResult> kept = renderer.render(*steps[i].s, *steps[i].o);
    ASSERT_TRUE(kept.ok()) << kept.error().message;
    const RenderResult fresh = penumbra::testing::render_valid(*steps[i].s, *steps[i].o);
    ASSERT_EQ(kept->fluence.width(), fresh.fluence.width());
    const std::size_t n = std::size_t(fresh.fluence.width()) * fresh.fluence.height() * 3;
    EXPECT_EQ(std::memcmp(kept->fluence.data(), fresh.fluence.data(), n * sizeof(float)), 0)
        << "step " << i;
  }
  // A refused render leaves the renderer usable.
  RenderOptions bad = hrc;
  bad.bounces = 0;
  EXPECT_FALSE(renderer.render(a, bad).ok());
  EXPECT_TRUE(renderer.render(a, hrc).ok());
}

}  // namespace
