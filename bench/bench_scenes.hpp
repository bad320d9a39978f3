// Scenes the benchmarks, the quality tools and the scene generator (tools/make_scenes.cpp, which
// writes scenes/lights_*.json from lights_scene) share.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>

#include "penumbra/flatland/scene.hpp"

namespace penumbra::bench {

using namespace penumbra::flatland;

// `lights` small coloured disk lights (radius 2) scattered over a size x size grid, with a fixed
// set of walls, so the geometry is the same whatever the number of lights.
inline SceneDesc lights_scene(int size, int lights, unsigned seed = 1) {
  SceneDesc d;
  d.width = d.height = size;
  d.environment = {0.01f, 0.01f, 0.015f};
  const float s = float(size) / 512.0f;
  d.shapes.push_back({Box{{180 * s, 256 * s}, {12 * s, 220 * s}, 0}, Material{}});
  d.shapes.push_back({Box{{340 * s, 150 * s}, {160 * s, 10 * s}, 25}, Material{}});
  d.shapes.push_back({Segment{{300 * s, 420 * s}, {470 * s, 380 * s}, 6 * s}, Material{}});
  d.shapes.push_back({Circle{{400 * s, 280 * s}, 30 * s}, Material{}});
  std::mt19937 rng(seed);
  // 24 random bits to [0, 1): unlike std::uniform_real_distribution, the same on every standard
  // library, so the generated scene files do not depend on the compiler.
  auto u = [&rng] { return float(rng() >> 8) * 0x1p-24f; };
  for (int i = 0; i < lights; ++i) {
    const float x = (8 + u() * 496) * s, y = (8 + u() * 496) * s;
    const float k = 4.0f / std::sqrt(float(std::max(lights, 1)) / 2.0f);
    d.shapes.push_back({Circle{{x, y}, 2 * s}, Material{{k * u(), k * u(), k * u()}, 1, {}}});
  }
  return d;
}

}  // namespace penumbra::bench
