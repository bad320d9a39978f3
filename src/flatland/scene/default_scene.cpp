// The built-in scene: three coloured lights, walls that cast soft penumbrae, a wall with a gap,
// a polygon and a faint fog box, with some albedo for bounces.
#include "penumbra/flatland/scene.hpp"

namespace penumbra::flatland {
namespace {

Shape light(float x, float y, float r, Rgb emission) {
  return {Circle{{x, y}, r}, Material{emission, 1, {}}};
}

Shape wall_box(float x, float y, float w, float h, float angle, Rgb albedo) {
  return {Box{{x, y}, {w, h}, angle}, Material{{}, 1, albedo}};
}

}  // namespace

SceneDesc default_scene() {
  SceneDesc d;
  d.width = 512;
  d.height = 384;
  d.environment = {0.02f, 0.02f, 0.03f};
  d.source = "<default scene>";

  // Lights: warm orange, cyan, magenta.
  d.shapes.push_back(light(88, 92, 11, {6.0f, 3.0f, 0.8f}));
  d.shapes.push_back(light(430, 70, 8, {0.6f, 4.5f, 5.5f}));
  d.shapes.push_back(light(372, 322, 13, {4.5f, 0.8f, 3.8f}));

  // Opaque walls, some rotated, casting penumbrae from the lights.
  d.shapes.push_back(wall_box(190, 170, 14, 130, 0, {0.7f, 0.7f, 0.7f}));
  d.shapes.push_back(wall_box(318, 168, 110, 12, 35, {0.8f, 0.6f, 0.5f}));
  d.shapes.push_back({Segment{{40, 250}, {165, 330}, 6}, Material{{}, 1, {0.55f, 0.65f, 0.8f}}});

  // A thin horizontal wall with a gap above the magenta light, which shines through it.
  d.shapes.push_back(wall_box(295, 262, 130, 3, 0, {0.6f, 0.6f, 0.6f}));
  d.shapes.push_back(wall_box(451, 262, 122, 3, 0, {0.6f, 0.6f, 0.6f}));

  // A concave polygon (an arrowhead).
  d.shapes.push_back({Polygon{{{96, 180}, {150, 200}, {118, 212}, {128, 250}}},
                      Material{{}, 1, {0.5f, 0.7f, 0.5f}}});

  // Faint fog: light passes but is dimmed and scattered a little.
  d.shapes.push_back({Box{{300, 90}, {120, 70}, 0}, Material{{}, 0.05f, {0.6f, 0.6f, 0.6f}}});
  return d;
}

}  // namespace penumbra::flatland
