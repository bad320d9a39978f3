// penumbra::spaceland::Renderer: a renderer kept from view to view gives render()'s bits whatever
// it rendered before; it keeps the ray tracer's BVH and the surface method's atlas while only the
// camera moves, and builds them again when anything else the image depends on changes (the
// scene but its camera, the surface options, the bounces).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <functional>
#include <iomanip>
#include <sstream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/scene_builders.hpp"
#include "test_support.hpp"

namespace penumbra::spaceland {
namespace {

using namespace penumbra::spaceland::testing;

// The materials of yard(), by index.
constexpr std::uint32_t kFloor = 0, kBox = 1, kBall = 2, kLamp = 3;

Camera camera_a() {
  return camera({0, 2, 4}, {0, 0.3f, 0}, 48, 36, 60);
}
Camera camera_b() {
  return camera({3, 1.5f, 1.5f}, {-0.2f, 0.4f, -0.3f}, 40, 32, 55);
}

// A floor (a disk of radius 3), a box (a mesh) and a glossy ball on it, a sphere lamp over them,
// a sky and the sun: every kind of shape, light and lobe the methods read, seen from `c`.
Scene yard(const Camera& c = camera_a()) {
  Scene s;
  s.camera = c;
  s.sky = {{0.2f, 0.3f, 0.5f}, {0.3f, 0.3f, 0.3f}, {0.1f, 0.1f, 0.1f}};
  s.has_sun = true;
  s.sun.direction = normalize(Vec3{0.4f, 0.8f, 0.3f});
  s.sun.irradiance = {2, 2, 2};
  add_floor(s, 3, {0.5f, 0.5f, 0.5f});  // material kFloor
  add_box(s, {-1.2f, 0, -0.8f}, {-0.4f, 0.8f, 0}, add_material(s, {0.7f, 0.3f, 0.2f}));  // kBox
  add_sphere(s, {0.6f, 0.5f, 0.2f}, 0.5f, add_material(s, {0.3f, 0.6f, 0.3f}));          // kBall
  s.materials[kBall].roughness = 0.5f;
  add_sphere(s, {0.1f, 1.4f, -0.6f}, 0.2f, add_material(s, {}, {10, 10, 10}));  // kLamp
  return s;
}

// Each method with small settings (a few milliseconds a render at 48 x 36).
RenderOptions options(Method m) {
  RenderOptions o;
  o.method = m;
  o.pt.spp = 2;
  o.pt.seed = 7;
  o.spwi.directions = 16;
  o.grid.voxel = 0.2f;
  o.grid.levels = 1;
  o.surface.texels = 1024;
  o.surface.directions = 16;
  return o;
}

RenderResult render_kept(Renderer& renderer, const Scene& s, const RenderOptions& o) {
  Expected<RenderResult> r = renderer.render(s, o);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? std::move(*r) : RenderResult{};
}

std::vector<std::string> stage_names(const RenderResult& r) {
  std::vector<std::string> names;
  for (const StageTime& st : r.stages) names.push_back(st.name);
  return names;
}

std::string stage_list(const RenderResult& r) {
  std::string list = "stages:";
  for (const StageTime& st : r.stages) {
    list += " [";
    list += st.name;
    list += "]";
  }
  return list;
}

bool has_stage(const RenderResult& r, const std::string& name) {
  for (const StageTime& st : r.stages)
    if (st.name == name) return true;
  return false;
}

// The BVH was built for this render.
bool built_bvh(const RenderResult& r) {
  return has_stage(r, "build BVH");
}

// The surface atlas was baked for this render: the bake's own stages (src/spaceland/atlas:
// "atlas", "probes", "sun", "bounce N cascade i", "bounce N irradiance") and the seams' links.
bool baked(const RenderResult& r) {
  return has_stage(r, "atlas") && has_stage(r, "probes") && has_stage(r, "bounce 1 cascade 0") &&
         has_stage(r, "seams");
}

// A render that kept both: the camera's first hits and the view over the kept atlas only.
void expect_kept_all(const RenderResult& r, const std::string& what) {
  EXPECT_EQ(stage_names(r), (std::vector<std::string>{"G-buffer", "view"}))
      << what << ": " << stage_list(r);
}

// The parameters describe() reports (the derived values the method used), one string each.
std::vector<std::string> parameters(const RenderResult& r) {
  std::vector<std::string> list;
  for (const Parameter& p : describe(r)) {
    std::ostringstream s;
    s << p.name << '=' << std::setprecision(17);
    std::visit([&](const auto& v) { s << v; }, p.value);
    list.push_back(s.str());
  }
  return list;
}

// The same image, bit for bit (memcmp of the floats), naming the first pixel that differs.
::testing::AssertionResult same_bits(const ImageRgb& a, const ImageRgb& b) {
  if (a.width() != b.width() || a.height() != b.height() || a.size() != b.size())
    return ::testing::AssertionFailure() << "sizes differ: " << a.width() << "x" << a.height()
                                         << " against " << b.width() << "x" << b.height();
  if (a.size() == 0) return ::testing::AssertionFailure() << "empty images";
  if (std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0)
    return ::testing::AssertionSuccess();
  std::size_t differ = 0, first = a.size();
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(a.data() + i, b.data() + i, sizeof(float)) != 0) {
      if (first == a.size()) first = i;
      ++differ;
    }
  const std::size_t px = first / 3;
  return ::testing::AssertionFailure()
         << differ << " of " << a.size() << " floats differ, the first at pixel ("
         << px % std::size_t(a.width()) << ", " << px / std::size_t(a.width()) << ") channel "
         << first % 3 << ": " << std::setprecision(9) << a.data()[first] << " against "
         << b.data()[first];
}

// The Renderer's result is render()'s: the image bit for bit, the samples, the parameters it
// derived and the warnings.
void expect_same(const RenderResult& kept, const RenderResult& fresh, const std::string& what) {
  EXPECT_TRUE(same_bits(kept.radiance, fresh.radiance))
      << what << "; the renderer's " << stage_list(kept) << "; render()'s " << stage_list(fresh);
  EXPECT_EQ(kept.samples, fresh.samples) << what;
  EXPECT_EQ(parameters(kept), parameters(fresh)) << what;
  EXPECT_EQ(kept.warnings, fresh.warnings) << what;
  EXPECT_FALSE(kept.cancelled) << what;
}

// Renders with `renderer` and with render(), expects the same, and returns the renderer's.
RenderResult render_both(Renderer& renderer, const Scene& s, const RenderOptions& o,
                         const std::string& what) {
  RenderResult kept = render_kept(renderer, s, o);
  expect_same(kept, render_ok(s, o), what);
  return kept;
}

const Method kMethods[] = {Method::ssrc, Method::spwi, Method::grid, Method::surface, Method::pt};

TEST(Renderer3d, EveryMethodGivesRendersBitsFromCameraAThenBThenA) {
  for (Method m : kMethods) {
    const RenderOptions o = options(m);
    Renderer renderer;
    const Camera cameras[] = {camera_a(), camera_b(), camera_a()};
    for (int i = 0; i < 3; ++i) {
      // A new Scene object each view (as a viewer's reload makes): nothing kept may point into
      // the last one.
      const Scene s = yard(cameras[i]);
      const std::string what = std::string(to_string(m)) + ", view " + std::to_string(i);
      const RenderResult r = render_both(renderer, s, o, what);
      // The BVH is built for the first view only.
      EXPECT_EQ(built_bvh(r), i == 0) << what << ": " << stage_list(r);
      if (m == Method::surface) {
        EXPECT_EQ(baked(r), i == 0) << what << ": " << stage_list(r);
        if (i > 0) expect_kept_all(r, what);
      }
    }
  }
}

// One renderer through every method and AOVs, each render()'s: the BVH is built once, and the
// surface method's atlas survives the renders of the methods that keep nothing (ssrc, spwi, pt)
// and of the AOVs. After the grid (which keeps its own solve in the renderer) only render()'s
// bits are asserted.
TEST(Renderer3d, OneRendererThroughEveryMethodKeepsTheBvhAndTheAtlas) {
  Renderer renderer;
  RenderOptions depth = options(Method::surface);
  depth.aov = Aov::depth;
  RenderOptions object = options(Method::ssrc);
  object.aov = Aov::object;
  struct Step {
    Camera camera;
    RenderOptions o;
    bool kept_atlas;  // a surface radiance render that must not bake
  };
  // G-buffer AOVs keep the atlas; a radiance render by another method drops it (one method's
  // state at a time), so the surface method bakes again after it.
  const std::vector<Step> steps = {{camera_a(), options(Method::surface), false},
                                   {camera_a(), depth, false},
                                   {camera_b(), object, false},
                                   {camera_b(), options(Method::surface), true},
                                   {camera_b(), options(Method::ssrc), false},
                                   {camera_a(), options(Method::surface), false},
                                   {camera_b(), options(Method::spwi), false},
                                   {camera_a(), options(Method::pt), false},
                                   {camera_b(), options(Method::grid), false},
                                   {camera_a(), options(Method::grid), false},
                                   {camera_b(), options(Method::surface), false},
                                   {camera_a(), options(Method::surface), true}};
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const std::string what = "step " + std::to_string(i) + " (" + to_string(steps[i].o.method) +
                             ", " + to_string(steps[i].o.aov) + ")";
    const RenderResult r = render_both(renderer, yard(steps[i].camera), steps[i].o, what);
    EXPECT_EQ(built_bvh(r), i == 0) << what << ": " << stage_list(r);
    if (steps[i].kept_atlas) expect_kept_all(r, what);
  }
}

// The grid keeps its solved levels while they stay where they were placed: one grid over the
// scene (levels 1) does not move with the camera, at any image size or a larger memory limit;
// under a limit too small for it the Renderer refuses as render() does.
TEST(Renderer3d, GridKeepsItsSolvedLevelsAcrossViewsAndSizes) {
  Renderer renderer;
  RenderOptions o = options(Method::grid);
  auto solved = [](const RenderResult& r) {
    for (const StageTime& st : r.stages)
      if (st.name == "cascades") return true;
    return false;
  };
  const RenderResult first = render_both(renderer, yard(camera_a()), o, "camera a");
  EXPECT_TRUE(solved(first)) << stage_list(first);
  const RenderResult b = render_both(renderer, yard(camera_b()), o, "camera b");
  EXPECT_FALSE(solved(b)) << stage_list(b);
  Camera big = camera_a();
  big.width = 96;
  big.height = 72;
  const RenderResult c = render_both(renderer, yard(big), o, "camera a, 96x72");
  EXPECT_FALSE(solved(c)) << stage_list(c);
  RenderOptions more = o;
  more.max_memory *= 2;
  const RenderResult d = render_both(renderer, yard(camera_b()), more, "a larger limit");
  EXPECT_FALSE(solved(d)) << stage_list(d);
  RenderOptions less = o;
  less.max_memory = d.voxel_bytes * 2;  // not even the voxels' quarter
  Expected<RenderResult> refused = renderer.render(yard(camera_b()), less);
  Expected<RenderResult> alone = render(yard(camera_b()), less);
  ASSERT_FALSE(refused.ok());
  ASSERT_FALSE(alone.ok());
  EXPECT_EQ(refused.error().message, alone.error().message);
}

// The yard's light changed as a viewer's panel changes it: the sun turned and the sky's zenith
// another colour (`k`: which of a few), which the grid's cascades carry.
void relight(Scene& s, int k) {
  const Vec3 suns[] = {{-0.5f, 0.7f, 0.2f}, {0.2f, 0.6f, -0.6f}, {0.4f, 0.8f, 0.3f}};
  s.sun.direction = normalize(suns[k]);
  s.sky.zenith = {0.1f + 0.2f * float(k), 0.3f, 0.5f - 0.1f * float(k)};
}

// Renders `s` with the renderer until the grid it asks for is shown (RenderResult::grid_slabs
// 0), checking each frame in between: the slabs done grow from `done` by 1..`slabs` a frame
// towards a total that stays the same. Returns the last frame; `frames` counts them.
RenderResult render_until_solved(Renderer& renderer, const Scene& s, const RenderOptions& o,
                                 std::uint64_t done, int& frames) {
  const std::uint64_t slabs = std::uint64_t(o.temporal.grid_slabs);
  std::uint64_t total = 0;
  RenderResult r;
  frames = 0;
  do {
    r = render_kept(renderer, s, o);
    ++frames;
    if (r.grid_slabs == 0) break;
    EXPECT_GT(r.grid_slabs_done, done) << "frame " << frames;
    EXPECT_LE(r.grid_slabs_done, done + slabs) << "frame " << frames;
    EXPECT_LT(r.grid_slabs_done, r.grid_slabs) << "frame " << frames;
    if (total > 0) {
      EXPECT_EQ(r.grid_slabs, total) << "frame " << frames;
    }
    EXPECT_FALSE(has_stage(r, "build BVH") && frames > 1) << stage_list(r);
    done = r.grid_slabs_done;
    total = r.grid_slabs;
  } while (frames < 10000);
  return r;
}

// With temporal.grid_slabs a grid solved again (here: the sun and the sky changed) is solved that
// many slabs a frame while the last one is shown: the first view is solved whole, render()'s bits;
// then each frame shows the old grid (another image than render()'s of the moved sun) and counts
// the new grid's slabs; the frame that finishes it is render()'s bit for bit. The slabs are z
// layers of probes, which read only the finished cascade above them: however a solve is split, its
// field is the same. One and two bounces (the voxels lit by the first solve before the second).
TEST(Renderer3d, GridSolvedASlabAtATimeShowsTheLastGridThenRendersBits) {
  for (int bounces : {1, 2}) {
    SCOPED_TRACE("bounces " + std::to_string(bounces));
    Renderer renderer;
    RenderOptions o = options(Method::grid);
    o.bounces = bounces;
    o.temporal.grid_slabs = 3;
    Scene s = yard();
    const RenderResult first = render_both(renderer, s, o, "first");
    EXPECT_EQ(first.grid_slabs, 0u);
    EXPECT_TRUE(has_stage(first, "cascades")) << stage_list(first);
    relight(s, 0);
    const RenderResult moved = render_ok(s, o);
    const RenderResult next = render_kept(renderer, s, o);
    ASSERT_GT(next.grid_slabs, 3u) << stage_list(next);
    EXPECT_EQ(next.grid_slabs_done, 3u);
    // The voxels are the scene's without its sky and sun: kept where no bounce lit them.
    EXPECT_EQ(has_stage(next, "voxelise"), bounces > 1) << stage_list(next);
    EXPECT_FALSE(same_bits(next.radiance, moved.radiance));
    int frames = 0;
    const RenderResult last = render_until_solved(renderer, s, o, next.grid_slabs_done, frames);
    // Every frame but the last took 3 slabs, the last the rest.
    EXPECT_EQ(std::uint64_t(frames + 1), (next.grid_slabs + 2) / 3);
    expect_same(last, moved, "the new grid shown");
    // The view kept: the grid is not solved again.
    const RenderResult again = render_kept(renderer, s, o);
    EXPECT_EQ(again.grid_slabs, 0u);
    EXPECT_FALSE(has_stage(again, "cascades")) << stage_list(again);
    expect_same(again, moved, "again");
  }
}

// A solve under way goes on to its end though the view moves on (a flying camera moves the
// levels nearly every frame); then the view's own grid is solved the same way, and shown as
// render() draws it. Without temporal.grid_slabs a changed view is solved whole at once, over
// the last grid's voxels where only the sky and the sun changed.
TEST(Renderer3d, GridSlabsFinishTheSolveUnderWayThenTheViewsOwn) {
  Renderer renderer;
  RenderOptions o = options(Method::grid);
  o.temporal.grid_slabs = 4;
  Scene s = yard();
  render_both(renderer, s, o, "first");
  relight(s, 0);
  const RenderResult started = render_kept(renderer, s, o);
  ASSERT_GT(started.grid_slabs, 8u);
  relight(s, 1);
  const RenderResult on = render_kept(renderer, s, o);
  EXPECT_EQ(on.grid_slabs_done, 8u) << "the solve under way did not go on";
  int frames = 0;
  RenderResult r = render_until_solved(renderer, s, o, on.grid_slabs_done, frames);
  // The first solve's grid is shown, not the view's: its own solve starts with the next frame.
  ASSERT_EQ(r.grid_slabs, 0u);
  r = render_kept(renderer, s, o);
  EXPECT_GT(r.grid_slabs, 0u) << "the view's own grid was not solved";
  r = render_until_solved(renderer, s, o, r.grid_slabs_done, frames);
  expect_same(r, render_ok(s, o), "the view's own grid");
  RenderOptions whole = o;
  whole.temporal.grid_slabs = 0;
  relight(s, 2);
  const RenderResult at_once = render_both(renderer, s, whole, "solved whole");
  EXPECT_EQ(at_once.grid_slabs, 0u);
  EXPECT_TRUE(has_stage(at_once, "cascades")) << stage_list(at_once);
  EXPECT_FALSE(has_stage(at_once, "voxelise")) << stage_list(at_once);
  // Another scene: voxelised again.
  Scene other = s;
  other.spheres[0].radius *= 1.1f;
  const RenderResult changed = render_both(renderer, other, whole, "another scene");
  EXPECT_TRUE(has_stage(changed, "voxelise")) << stage_list(changed);
  // With one bounce the cascades see the sky without the sun's disk (each pixel takes the sun
  // through its own shadow ray): a moved sun keeps the grid, and the frame is still render()'s.
  Scene sunny = other;
  sunny.sun.direction = normalize(Vec3{-0.3f, 0.9f, 0.1f});
  const RenderResult sun_moved = render_both(renderer, sunny, o, "the sun moved, one bounce");
  EXPECT_FALSE(has_stage(sun_moved, "cascades")) << stage_list(sun_moved);
  EXPECT_EQ(sun_moved.grid_slabs, 0u);
}

TEST(Renderer3d, SurfaceKeepsTheAtlasAndTheBvhWhenOnlyTheCameraMoves) {
  const RenderOptions o = options(Method::surface);
  Renderer renderer;
  const RenderResult first = render_both(renderer, yard(camera_a()), o, "camera A");
  const RenderResult second = render_both(renderer, yard(camera_b()), o, "camera B");
  std::printf("renderer_test: the surface method's first view, %s; the second, %s\n",
              stage_list(first).c_str(), stage_list(second).c_str());
  // The first: the BVH, the bake's stages, its cascades and the seams; then the view.
  EXPECT_TRUE(built_bvh(first)) << stage_list(first);
  EXPECT_TRUE(baked(first)) << stage_list(first);
  EXPECT_TRUE(has_stage(first, "view")) << stage_list(first);
  // The second: none of them.
  EXPECT_FALSE(built_bvh(second)) << stage_list(second);
  for (const StageTime& st : second.stages) {
    EXPECT_EQ(st.name.find("cascade"), std::string::npos) << stage_list(second);
    EXPECT_EQ(st.name.find("irradiance"), std::string::npos) << stage_list(second);
  }
  expect_kept_all(second, "camera B");
  // The kept atlas's derived parameters are reported as the bake's.
  EXPECT_EQ(parameters(first), parameters(second));
  // No bake's rays in the second.
  EXPECT_LT(second.rays, first.rays);
}

// Anything but the camera changed between views, one thing at a time (each change on top of the
// last, so that each view differs from the last in that alone): the renderer's image is
// render()'s of the changed scene, with the BVH built again and the atlas baked again; the next
// camera move keeps the new ones.
void expect_changes_seen(Method m) {
  const std::vector<std::pair<std::string, std::function<void(Scene&)>>> changes = {
      {"the sun's direction",
       [](Scene& s) {
         s.sun.direction = normalize(Vec3{-0.5f, 0.7f, 0.2f});
       }},
      {"the sun's irradiance",
       [](Scene& s) {
         s.sun.irradiance = {3, 2, 1};
       }},
      {"the sun's radius", [](Scene& s) { s.sun.angular_radius = 2; }},
      {"the box's albedo",
       [](Scene& s) {
         s.materials[kBox].albedo = {0.2f, 0.4f, 0.8f};
       }},
      {"the ball's roughness (glossy to Lambertian)",
       [](Scene& s) { s.materials[kBall].roughness = 1; }},
      {"the ball's metallic (Lambertian to glossy)",
       [](Scene& s) { s.materials[kBall].metallic = 1; }},
      {"the lamp's emission",
       [](Scene& s) {
         s.materials[kLamp].emission = {20, 5, 5};
       }},
      {"the ball moved", [](Scene& s) { s.spheres[0].center.x += 0.3f; }},
      {"the lamp's radius", [](Scene& s) { s.spheres[1].radius = 0.25f; }},
      {"the box moved",
       [](Scene& s) {
         for (Vec3& p : s.meshes[0].positions) p.z -= 0.4f;
       }},
      {"the floor's radius", [](Scene& s) { s.disks[0].radius = 2.5f; }},
      {"the floor tilted",
       [](Scene& s) {
         s.disks[0].normal = normalize(Vec3{0.1f, 1, 0});
       }},
      {"the sky",
       [](Scene& s) {
         s.sky.zenith = {0.5f, 0.1f, 0.1f};
       }},
      {"a sphere more",
       [](Scene& s) {
         add_sphere(s, {-0.5f, 1.2f, 0.6f}, 0.15f, kFloor);
       }},
      {"no sun", [](Scene& s) { s.has_sun = false; }},
      {"a lamp beyond the float range (rendered dimmed)",
       [](Scene& s) {
         s.materials[kLamp].emission = {3e35f, 3e35f, 3e35f};
       }},
  };
  const RenderOptions o = options(m);
  Renderer renderer;
  render_both(renderer, yard(camera_a()), o, "the first view");
  Scene s = yard(camera_b());
  for (const auto& [name, change] : changes) {
    const std::string what = std::string(to_string(m)) + ", " + name;
    s.camera = camera_b();
    change(s);
    const RenderResult after = render_both(renderer, s, o, what);
    EXPECT_TRUE(built_bvh(after)) << what << ": " << stage_list(after);
    if (m == Method::surface) {
      EXPECT_TRUE(baked(after)) << what << ": " << stage_list(after);
    }
    // The changed scene from another camera: kept.
    s.camera = camera_a();
    const RenderResult kept = render_both(renderer, s, o, what + ", moved");
    EXPECT_FALSE(built_bvh(kept)) << what << ": " << stage_list(kept);
    if (m == Method::surface) expect_kept_all(kept, what + ", moved");
  }
  // And back to the first scene: built and baked again.
  const RenderResult back = render_both(renderer, yard(camera_b()), o, "back to the first scene");
  EXPECT_TRUE(built_bvh(back)) << stage_list(back);
  if (m == Method::surface) {
    EXPECT_TRUE(baked(back)) << stage_list(back);
  }
}

TEST(Renderer3d, SurfaceSeesChangesButTheCameraAndBakesAgain) {
  expect_changes_seen(Method::surface);
}

TEST(Renderer3d, SsrcSeesChangesButTheCameraAndBuildsTheBvhAgain) {
  expect_changes_seen(Method::ssrc);
}

// Fog (which the surface method refuses) through the methods that carry it: added, thickened or
// moved between views, the BVH is built again and the image is render()'s.
TEST(Renderer3d, FogChangedBetweenViewsIsSeen) {
  Medium fog;
  fog.center = {0, 0.6f, 0};
  fog.half_size = {1.5f, 0.6f, 1.5f};
  fog.extinction = {0.3f, 0.3f, 0.3f};
  fog.albedo = {0.5f, 0.5f, 0.5f};
  for (Method m : {Method::grid, Method::pt}) {
    const RenderOptions o = options(m);
    const std::string method = to_string(m);
    Renderer renderer;
    render_both(renderer, yard(camera_a()), o, method + ": no fog");
    Scene s = yard(camera_a());
    s.media.push_back(fog);
    RenderResult r = render_both(renderer, s, o, method + ": fog added");
    EXPECT_TRUE(built_bvh(r)) << stage_list(r);
    s.camera = camera_b();
    r = render_both(renderer, s, o, method + ": fog, moved");
    EXPECT_FALSE(built_bvh(r)) << stage_list(r);
    s.media[0].extinction = {0.6f, 0.3f, 0.1f};
    r = render_both(renderer, s, o, method + ": fog thicker");
    EXPECT_TRUE(built_bvh(r)) << stage_list(r);
    s.media[0].center.x += 0.5f;
    r = render_both(renderer, s, o, method + ": fog moved");
    EXPECT_TRUE(built_bvh(r)) << stage_list(r);
    s.media[0].emission = {0.1f, 0.1f, 0.1f};
    r = render_both(renderer, s, o, method + ": fog glowing");
    EXPECT_TRUE(built_bvh(r)) << stage_list(r);
  }
}

// The surface options the atlas is made with, or the bounces, changed between views (each on top
// of the last): baked again over the kept BVH; options it is not made with (the sun's rays at the
// view, the threads, the memory limit, an AOV between) keep it.
TEST(Renderer3d, OtherSurfaceOptionsOrBouncesBakeAgain) {
  const RenderOptions base = options(Method::surface);
  const std::vector<std::pair<std::string, std::function<void(RenderOptions&)>>> rebake = {
      {"texels", [](RenderOptions& o) { o.surface.texels = 512; }},
      {"refine", [](RenderOptions& o) { o.surface.refine = 0; }},
      {"interval", [](RenderOptions& o) { o.surface.interval = 0.2f; }},
      {"cascades", [](RenderOptions& o) { o.surface.cascades = 2; }},
      {"texel_size", [](RenderOptions& o) { o.surface.texel_size = 0.2f; }},
      {"directions", [](RenderOptions& o) { o.surface.directions = 64; }},
      {"bounces", [](RenderOptions& o) { o.bounces = 2; }},
  };
  Renderer renderer;
  render_both(renderer, yard(camera_a()), base, "the first options");
  RenderOptions o = base;
  for (const auto& [name, change] : rebake) {
    change(o);
    const RenderResult r = render_both(renderer, yard(camera_b()), o, name);
    EXPECT_FALSE(built_bvh(r)) << name << ": " << stage_list(r);
    EXPECT_TRUE(baked(r)) << name << ": " << stage_list(r);
    const RenderResult kept = render_both(renderer, yard(camera_a()), o, name + ", moved");
    expect_kept_all(kept, name + ", moved");
  }
  // Back to the first options: one atlas is kept, so baked again.
  const RenderResult back = render_both(renderer, yard(camera_b()), base, "the first options");
  EXPECT_FALSE(built_bvh(back)) << stage_list(back);
  EXPECT_TRUE(baked(back)) << stage_list(back);

  const std::vector<std::pair<std::string, std::function<void(RenderOptions&)>>> keep = {
      {"sun_rays", [](RenderOptions& o) { o.sun_rays = 4; }},
      {"threads 1", [](RenderOptions& o) { o.threads = 1; }},
      {"threads 2", [](RenderOptions& o) { o.threads = 2; }},
      {"max_memory", [](RenderOptions& o) { o.max_memory = std::uint64_t(1) << 30; }},
  };
  for (const auto& [name, change] : keep) {
    RenderOptions other = base;
    change(other);
    const RenderResult r = render_both(renderer, yard(camera_a()), other, name);
    expect_kept_all(r, name);
  }
  RenderOptions normal = base;
  normal.aov = Aov::normal;
  const RenderResult aov = render_both(renderer, yard(camera_a()), normal, "AOV normal");
  EXPECT_EQ(stage_names(aov), (std::vector<std::string>{"G-buffer", "AOV"})) << stage_list(aov);
  expect_kept_all(render_both(renderer, yard(camera_b()), base, "after the AOV"), "after the AOV");
}

TEST(Renderer3d, ClearedAndMovedFromRenderersRenderAgain) {
  const RenderOptions o = options(Method::surface);
  Renderer renderer;
  render_both(renderer, yard(camera_a()), o, "first");
  renderer.clear();
  RenderResult r = render_both(renderer, yard(camera_b()), o, "after clear()");
  EXPECT_TRUE(built_bvh(r)) << stage_list(r);
  EXPECT_TRUE(baked(r)) << stage_list(r);
  renderer.clear();
  renderer.clear();  // twice: nothing to drop
  r = render_both(renderer, yard(camera_a()), o, "after clear() twice");
  EXPECT_TRUE(baked(r)) << stage_list(r);

  // Moved: the new one holds what was kept, the moved-from one starts afresh.
  Renderer moved(std::move(renderer));
  r = render_both(moved, yard(camera_b()), o, "move-constructed");
  expect_kept_all(r, "move-constructed");
  r = render_both(renderer, yard(camera_b()), o, "moved-from");  // NOLINT(bugprone-use-after-move)
  EXPECT_TRUE(built_bvh(r)) << stage_list(r);
  EXPECT_TRUE(baked(r)) << stage_list(r);

  Renderer assigned;
  assigned = std::move(moved);
  r = render_both(assigned, yard(camera_a()), o, "move-assigned");
  expect_kept_all(r, "move-assigned");
  moved.clear();  // NOLINT(bugprone-use-after-move): clear() on a moved-from renderer
  r = render_both(moved, yard(camera_a()), o, "moved-from, cleared");
  EXPECT_TRUE(baked(r)) << stage_list(r);
  // Assigned over one that held an atlas: the assigned one's is kept.
  renderer = std::move(assigned);
  r = render_both(renderer, yard(camera_b()), o, "assigned over");
  expect_kept_all(r, "assigned over");
}

// A refused render returns its Error and leaves the renderer working: refused options or scene
// before anything is touched (the atlas still kept), an atlas file that cannot be read after the
// BVH is built.
TEST(Renderer3d, ARefusedRenderLeavesTheRendererWorking) {
  const RenderOptions o = options(Method::surface);
  Renderer renderer;
  render_both(renderer, yard(camera_a()), o, "first");

  RenderOptions bad = o;
  bad.surface.directions = 5;
  Expected<RenderResult> refused = renderer.render(yard(camera_b()), bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("`surface.directions`"), std::string::npos)
      << refused.error().message;
  expect_kept_all(render_both(renderer, yard(camera_b()), o, "after refused options"),
                  "after refused options");

  Scene invalid = yard(camera_b());
  invalid.spheres[0].material = 99;  // no such material
  refused = renderer.render(invalid, o);
  EXPECT_FALSE(refused.ok());
  expect_kept_all(render_both(renderer, yard(camera_a()), o, "after a refused scene"),
                  "after a refused scene");

  RenderOptions small = o;
  small.max_memory = 1 << 10;
  refused = renderer.render(yard(camera_a()), small);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("max_memory"), std::string::npos)
      << refused.error().message;
  expect_kept_all(render_both(renderer, yard(camera_b()), o, "after too little memory"),
                  "after too little memory");

  // Fog, which the surface method refuses, in a scene the renderer has not seen.
  Scene foggy = yard(camera_a());
  Medium fog;
  fog.extinction = {0.5f, 0.5f, 0.5f};
  foggy.media.push_back(fog);
  refused = renderer.render(foggy, o);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("fog"), std::string::npos) << refused.error().message;
  expect_kept_all(render_both(renderer, yard(camera_b()), o, "after fog refused"),
                  "after fog refused");

  // An atlas file that is not there: refused once the BVH is built (for another scene here).
  penumbra::testing::TestDir dir("renderer");
  RenderOptions missing = o;
  missing.surface.atlas = dir.file("missing.exr");
  Scene other = yard(camera_a());
  other.materials[kBox].albedo = {0.1f, 0.1f, 0.1f};
  refused = renderer.render(other, missing);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("missing.exr"), std::string::npos)
      << refused.error().message;
  RenderResult r = render_both(renderer, other, o, "the other scene after a missing atlas");
  EXPECT_TRUE(baked(r)) << stage_list(r);
  r = render_both(renderer, yard(camera_b()), o, "the first scene after a missing atlas");
  EXPECT_TRUE(built_bvh(r)) << stage_list(r);
  EXPECT_TRUE(baked(r)) << stage_list(r);
}

// A view from an atlas file: read once while only the camera moves, and render()'s bits.
TEST(Renderer3d, AnAtlasFileIsReadOnceForItsViews) {
  penumbra::testing::TestDir dir("renderer");
  const std::string path = dir.file("yard.exr");
  const Expected<BakeResult> made = bake(yard(), options(Method::surface), path);
  ASSERT_TRUE(made.ok()) << made.error().message;
  RenderOptions view = options(Method::surface);
  view.surface.atlas = path;
  Renderer renderer;
  const RenderResult first = render_both(renderer, yard(camera_a()), view, "read");
  EXPECT_TRUE(has_stage(first, "read atlas")) << stage_list(first);
  const RenderResult second = render_both(renderer, yard(camera_b()), view, "moved");
  expect_kept_all(second, "moved");
}

// The atlas file baked again (another texel budget, the same scene) between two views from it:
// render() reads the new file, and so must the renderer.
TEST(Renderer3d, AnAtlasFileBakedAgainBetweenViewsIsReadAgain) {
  penumbra::testing::TestDir dir("renderer");
  const std::string path = dir.file("yard.exr");
  RenderOptions coarse = options(Method::surface);
  coarse.surface.texels = 512;
  ASSERT_TRUE(bake(yard(), coarse, path).ok());
  RenderOptions view = options(Method::surface);
  view.surface.atlas = path;
  Renderer renderer;
  render_both(renderer, yard(camera_a()), view, "the first file");
  RenderOptions fine = options(Method::surface);
  fine.surface.texels = 4096;
  ASSERT_TRUE(bake(yard(), fine, path).ok());
  const RenderResult r = render_both(renderer, yard(camera_b()), view, "the file baked again");
  EXPECT_TRUE(has_stage(r, "read atlas")) << stage_list(r);
}

// Only the objects' indices changed (a document's objects reordered: the same meshes, spheres
// and disks, each now another object): the object AOV names the new ones, as render()'s does.
TEST(Renderer3d, ObjectIndicesChangedBetweenViewsAreSeen) {
  RenderOptions o = options(Method::ssrc);
  o.aov = Aov::object;
  Renderer renderer;
  const Scene s = yard(camera_a());
  render_both(renderer, s, o, "before");
  Scene reordered = s;
  std::swap(reordered.meshes[0].object, reordered.spheres[0].object);
  std::swap(reordered.objects[std::size_t(reordered.meshes[0].object)],
            reordered.objects[std::size_t(reordered.spheres[0].object)]);
  const RenderResult r = render_both(renderer, reordered, o, "objects reordered");
  // The box's and the ball's pixels show the new indices.
  const ImageRgb before = render_ok(s, o).radiance, after = render_ok(reordered, o).radiance;
  ASSERT_FALSE(same_bits(before, after));
  EXPECT_FALSE(same_bits(r.radiance, before));
}

}  // namespace
}  // namespace penumbra::spaceland
