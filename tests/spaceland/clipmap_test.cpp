// The probe grid's levels around the camera (grid/clipmap.hpp): where they lie, rays going on
// through the coarser levels (an emitting enclosure's closed form across them), the blend between
// levels (a uniform sky over a wide floor, exact), the sphere lights each level spreads, and a
// small light over a wide floor against its closed form.
#include "spaceland/grid/clipmap.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "penumbra/spaceland/render.hpp"
#include "spaceland/grid/grid.hpp"
#include "spaceland/scene_builders.hpp"

namespace penumbra::spaceland::grid {
namespace {

using namespace penumbra::spaceland::testing;

// Level l's world box.
Bounds box_of(const Scene& s, const ClipLevel& l) {
  const Vec3 origin = grid_bounds(s).lo - Vec3{l.size, l.size, l.size} * float(kPadding);
  Bounds b;
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = origin[k] + float(l.box.first[std::size_t(k)]) * l.size;
    b.hi[k] = b.lo[k] + float(l.box.dims[std::size_t(k)]) * l.size;
  }
  return b;
}

TEST(Clipmap, LevelsDoubleAroundTheCameraAndTheLastHoldsTheScene) {
  const Scene s = wide_floor();
  const Vec3 camera{10, 2, 5};
  const std::vector<ClipLevel> levels = clip_levels(s, 0.1f, 0, camera);
  // 136 voxels of 0.1, 0.2 and 0.4 are narrower than the floor; of 0.8, 125 and the padding hold
  // it.
  ASSERT_EQ(levels.size(), 4u);
  for (std::size_t l = 0; l < levels.size(); ++l) {
    EXPECT_FLOAT_EQ(levels[l].size, 0.1f * float(1 << l));
    const Bounds b = box_of(s, levels[l]);
    const bool last = l + 1 == levels.size();
    for (int k : {0, 2}) {
      EXPECT_EQ(levels[l].box.dims[std::size_t(k)], last ? 133 : kLevelVoxels) << l;
      // Around the camera: it lies within a voxel of the box's middle.
      if (!last) {
        EXPECT_NEAR((b.lo[k] + b.hi[k]) / 2, camera[k], levels[l].size) << l;
      }
      EXPECT_EQ(levels[l].cut[std::size_t(k)][0], !last) << l;
      EXPECT_EQ(levels[l].cut[std::size_t(k)][1], !last) << l;
    }
    // The floor is flat: every level holds its height whole, with the padding.
    EXPECT_EQ(levels[l].box.dims[1], 2 * kPadding) << l;
    EXPECT_FALSE(levels[l].cut[1][0] || levels[l].cut[1][1]) << l;
  }
  EXPECT_EQ(clipmap_voxels(levels), 3 * 136 * 136 * 8 + 133 * 133 * 8);
  // A camera near the floor's edge: the level slides to stay within the scene.
  const std::vector<ClipLevel> edge = clip_levels(s, 0.1f, 0, {49, 2, 0});
  EXPECT_TRUE(edge[0].cut[0][0]);
  EXPECT_FALSE(edge[0].cut[0][1]);
  EXPECT_NEAR(box_of(s, edge[0]).hi.x, 50 + 0.1f * kPadding, 1e-3);
  // Asked for two levels: the second holds the whole scene, however many voxels that takes.
  const std::vector<ClipLevel> two = clip_levels(s, 0.1f, 2, camera);
  ASSERT_EQ(two.size(), 2u);
  EXPECT_EQ(two[1].box.dims[0], 500 + 2 * kPadding);
}

TEST(Clipmap, ASceneTheDefaultGridHoldsIsOneLevel) {
  Scene s;
  s.camera = camera({0, 0.5f, 3}, {0, 0, 0}, 32, 24);
  add_box(s, {-1, -1, -1}, {1, 1, 1}, add_material(s, {0.5f, 0.5f, 0.5f}));
  const GridOptions o;
  // The camera looks from 3 away: 3 / 32 is coarser than the longest side over 128.
  const std::vector<ClipLevel> levels = plan_levels(s, o, std::uint64_t(1) << 30, false, 3);
  ASSERT_EQ(levels.size(), 1u);
  EXPECT_FLOAT_EQ(levels[0].size, 2.0f / 128);
  EXPECT_EQ(levels[0].box.dims[0], 128 + 2 * kPadding);
  GridOptions one;
  one.levels = 1;
  const std::vector<ClipLevel> whole = plan_levels(s, one, std::uint64_t(1) << 30, false, 3);
  EXPECT_EQ(whole[0].box.first, levels[0].box.first);
  EXPECT_EQ(whole[0].box.dims, levels[0].box.dims);
  // Close up (0.3 away), the finest voxel follows what the camera sees: two levels.
  EXPECT_EQ(plan_levels(s, o, std::uint64_t(1) << 30, false, 0.3f).size(), 2u);
  // Bounds whose width rounds in float (3.1 - -0.3): still the one grid --levels 1 makes.
  Scene odd;
  add_box(odd, {-0.3f, -1, -1}, {3.1f, 1, 1}, add_material(odd, {0.5f, 0.5f, 0.5f}));
  const std::vector<ClipLevel> fits = plan_levels(odd, o, std::uint64_t(1) << 30, false, 3);
  ASSERT_EQ(fits.size(), 1u);
  EXPECT_EQ(fits[0].box.dims, plan_levels(odd, one, std::uint64_t(1) << 30, false, 3)[0].box.dims);
  // Extension keeps one grid (its shifted intervals read probes a level does not have past its
  // box); asked for with more levels, it is refused.
  GridOptions extend;
  extend.extend_length = 8;
  EXPECT_EQ(plan_levels(s, extend, std::uint64_t(1) << 30, false, 0.3f).size(), 1u);
  extend.levels = 2;
  const Status refused = check_options(extend);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("`grid.levels`: extension"), std::string::npos)
      << refused.error().message;
  // An interval given in world units is the finest level's: it doubles per level.
  GridOptions t0;
  t0.interval = 0.5f;
  EXPECT_FLOAT_EQ(level_options(t0, 0).interval, 0.5f);
  EXPECT_FLOAT_EQ(level_options(t0, 3).interval, 4.0f);
}

// Through render(): the camera inside an emitting box sees Le (1 + a + a^2) at 2 bounces
// everywhere, its rays leaving the finest level and going on through the next to the far walls;
// SPWI too, its second bounce read from the radiance cache's levels.
TEST(Clipmap, TheEnclosureStaysExactAcrossLevels) {
  Scene s;
  s.camera = camera({0.1f, 0.1f, 0.3f}, {3, 0.2f, -1}, 32, 24, 90);
  add_box(s, {-4, -0.5f, -4}, {4, 0.5f, 4}, add_material(s, {0.6f, 0.6f, 0.6f}, {1, 0.5f, 0.25f}));
  RenderOptions o;
  o.method = Method::grid;
  o.grid.voxel = 0.05f;
  o.bounces = 2;
  const RenderResult r = render_ok(s, o);
  EXPECT_EQ(r.options.grid.levels, 2);
  double worst = 0;
  for (int j = 0; j < 24; ++j)
    for (int i = 0; i < 32; ++i)
      worst = std::max(worst, std::abs(r.radiance.at(i, j).r / 1.96 - 1));
  EXPECT_LT(worst, 0.01);
  // The voxels reported are both levels'.
  EXPECT_EQ(r.voxel_bytes, voxel_bytes(136 * 28 * 136 + 88 * 18 * 88, true));
  // SPWI's later bounces from the radiance cache over the same levels.
  o.method = Method::spwi;
  const RenderResult spwi = render_ok(s, o);
  EXPECT_EQ(spwi.options.grid.levels, 2);
  worst = 0;
  for (int j = 0; j < 24; ++j)
    for (int i = 0; i < 32; ++i)
      worst = std::max(worst, std::abs(spwi.radiance.at(i, j).r / 1.96 - 1));
  EXPECT_LT(worst, 0.01);
}

// A uniform sky over a wide floor: every floor pixel is a L, whichever levels it reads.
TEST(Clipmap, AUniformSkyOverAWideFloorIsExactAcrossLevels) {
  Scene s;
  const Rgb l{1.5f, 1, 0.5f};
  s.sky = {l, l, l};
  s.camera = camera({0, 1.5f, 4}, {0, 0, -6}, 32, 24, 70);
  add_box(s, {-30, -0.2f, -30}, {30, 0, 30}, add_material(s, {0.6f, 0.6f, 0.6f}));
  RenderOptions o;
  o.method = Method::grid;
  const RenderResult r = render_ok(s, o);
  EXPECT_GE(r.options.grid.levels, 3);
  const FirstHits hits = first_hits(s);
  int floor = 0;
  double worst = 0;
  for (int j = 0; j < 24; ++j)
    for (int i = 0; i < 32; ++i)
      if (hits.object.at(i, j).r == 0) {
        ++floor;
        worst = std::max(worst, std::abs(r.radiance.at(i, j).r / (0.6 * 1.5) - 1));
      }
  EXPECT_GT(floor, 32 * 24 / 3);
  EXPECT_LT(worst, 1e-4);
}

// A level spreads the sphere lights under 4 voxels in radius of the level whose voxels its rays
// meet them in: its own, or, for a light outside its box, the finest level that holds it.
TEST(Clipmap, EachLevelSpreadsTheLightsItsRaysMeetInNoVoxels) {
  Scene s = wide_floor();
  const std::uint32_t lamp = add_material(s, {0, 0, 0}, {10, 10, 10});
  add_sphere(s, {0, 1, 0}, 0.3f, lamp);   // 3 voxels of level 0: spread everywhere
  add_sphere(s, {1, 1, 0}, 0.5f, lamp);   // 5 voxels of level 0, 2.5 of level 1
  add_sphere(s, {30, 1, 0}, 0.5f, lamp);  // out of levels 0 to 2: 1.25 voxels of level 3
  Expected<Clipmap> map =
      Clipmap::build(s, clip_levels(s, 0.1f, 0, {0, 1, 3}), std::uint64_t(1) << 30, 4);
  ASSERT_TRUE(map.ok()) << map.error().message;
  ASSERT_EQ(map->size(), 4u);
  EXPECT_EQ(map->lights(s, 0).size(), 2u);  // the first, and the far one
  for (std::size_t l = 1; l < 4; ++l) EXPECT_EQ(map->lights(s, l).size(), 3u) << l;
  // Level 0's voxels hold the second light (opaque where it is), not the first.
  const Voxels& v = (*map)[0];
  auto opaque_at = [&](Vec3 p) {
    return v.opaque(v.index(v.cell(p, 0), v.cell(p, 1), v.cell(p, 2)));
  };
  EXPECT_TRUE(opaque_at({1.5f, 1, 0}));
  EXPECT_FALSE(opaque_at({0.3f, 1, 0}));
  // With the fix's 2 voxels, level 0 voxelises the first light too.
  Expected<Clipmap> fix =
      Clipmap::build(s, clip_levels(s, 0.1f, 0, {0, 1, 3}), std::uint64_t(1) << 30, 2);
  ASSERT_TRUE(fix.ok());
  EXPECT_EQ(fix->lights(s, 0).size(), 1u);
}

// Measured 2026-11-27 (96 x 72): one grid over the floor (voxels of 0.78, the light spread
// over them) 1.79 in view and 0.35 behind; the levels (0.135 voxels near the camera) 0.32 and
// 0.175; with the light voxelised at 2.2 voxels of level 0 (the spread under 2 voxels before)
// 3.14 and 2.34: star-shaped blotches. With cascade 0's share met at the floor's points
// (RadianceField::lights_at): 3e-7 and 1e-6, one grid or the levels.
TEST(Clipmap, ASmallLightOverAWideFloorIsRightWhereTheCameraLooks) {
  RenderOptions o;
  o.method = Method::grid;
  EXPECT_LT(wide_floor_error(o, false), 0.01);
  EXPECT_LT(wide_floor_error(o, true), 0.01);
  // Cascade 0's share of the light is met at the floor's points, with the probes' reach for its
  // visibility: nothing hides it here, and one grid of 0.78 voxels gets it as right.
  o.grid.levels = 1;
  EXPECT_LT(wide_floor_error(o, false), 0.01);
  EXPECT_LT(wide_floor_error(o, true), 0.01);
}

}  // namespace
}  // namespace penumbra::spaceland::grid
