// The baked atlas as a file (issue 39: `penumbra bake`, `--atlas`): a view from the file gives
// the pixels a bake-and-view gives, from any camera; the closed forms hold through it; cascade
// 0's radiance per direction is in it; an atlas of another scene, of other bounces, or a damaged
// file is refused with the file named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <tuple>

#include "core/octahedral.hpp"
#include "io/image_io.hpp"
#include "spaceland/atlas/file.hpp"
#include "spaceland/color.hpp"
#include "spaceland/scene_builders.hpp"
#include "spaceland/surface.hpp"
#include "test_support.hpp"

namespace penumbra::spaceland {
namespace {

using namespace penumbra::spaceland::testing;

struct Dir : penumbra::testing::TestDir {
  Dir() : penumbra::testing::TestDir("atlas_file") {}
};

RenderOptions surface(int texels, int directions, int bounces = 1) {
  RenderOptions o;
  o.method = Method::surface;
  o.surface.texels = std::uint64_t(texels);
  o.surface.directions = directions;
  o.bounces = bounces;
  return o;
}

BakeResult bake_ok(const Scene& s, const RenderOptions& o, const std::string& path) {
  Expected<BakeResult> r = bake(s, o, path);
  EXPECT_TRUE(r) << (r ? "" : r.error().message);
  return r ? *r : BakeResult{};
}

bool same_bits(const ImageRgb& a, const ImageRgb& b) {
  return a.size() == b.size() && std::equal(a.data(), a.data() + a.size(), b.data());
}

// A sphere light (radius 0.3, Le 30) 1 over a floor of radius 2 (albedo 0.5).
Scene lamp_over_floor() {
  Scene s;
  s.camera = camera({0, 2, 3}, {0, 0, 0}, 24, 18, 60);
  add_floor(s, 2, {0.5f, 0.5f, 0.5f});
  add_sphere(s, {0.2f, 1, -0.1f}, 0.3f, add_material(s, {}, {30, 30, 30}));
  return s;
}

TEST(AtlasFile, AViewFromTheFileGivesTheBakesPixelsFromEveryCamera) {
  Dir dir;
  Scene s = lamp_over_floor();
  const RenderOptions o = surface(4096, 16);
  const BakeResult baked = bake_ok(s, o, dir.file("lamp.exr"));
  EXPECT_TRUE(baked.radiance);
  EXPECT_GT(baked.file_bytes, 0u);
  EXPECT_GT(baked.covered, 3000u);
  RenderOptions view = o;
  view.surface.atlas = dir.file("lamp.exr");
  for (const Camera& c : {s.camera, camera({2.5f, 0.6f, 0}, {0, 0, 0}, 20, 16, 70),
                          camera({-1, 3, -1}, {0.3f, 0, 0.2f}, 16, 16, 45)}) {
    s.camera = c;
    const RenderResult fresh = render_ok(s, o);
    const RenderResult from_file = render_ok(s, view);
    EXPECT_TRUE(same_bits(fresh.radiance, from_file.radiance));
    // No cascade traced: the stages read the file and view.
    for (const StageTime& st : from_file.stages)
      EXPECT_EQ(st.name.find("cascade"), std::string::npos) << st.name;
    EXPECT_NEAR(from_file.options.surface.texel_size, baked.used.texel_size, 0);
    EXPECT_EQ(from_file.options.surface.cascades, baked.used.cascades);
  }
}

// A scene brighter than the methods compute with is baked dimmed, and the file holds the light
// at that scale and says so (its irradiance, pi times the radiance, might pass a float at its
// true scale: a sky of 2e38): the view from the file still gives the bake-and-view's bits.
TEST(AtlasFile, ABrightSceneRoundTripsThroughItsDimmedScale) {
  Dir dir;
  Scene s = lamp_over_floor();
  s.materials.back().emission = {3e35f, 3e35f, 3e35f};
  Scene sky;
  sky.camera = s.camera;
  add_floor(sky, 2, {0, 0, 0});
  sky.sky.zenith = sky.sky.horizon = sky.sky.ground = {2e38f, 2e38f, 2e38f};
  for (const Scene& scene : {s, sky}) {
    const RenderOptions o = surface(1024, 16);
    bake_ok(scene, o, dir.file("bright.exr"));
    atlas::Record r;
    Expected<atlas::Baked> b =
        atlas::read_atlas(dir.file("bright.exr"), scene, std::uint64_t(1) << 32, r);
    ASSERT_TRUE(b) << b.error().message;
    EXPECT_GT(r.light_exponent, 0);
    RenderOptions view = o;
    view.surface.atlas = dir.file("bright.exr");
    const Expected<RenderResult> seen = render(scene, view);
    ASSERT_TRUE(seen) << seen.error().message;
    EXPECT_TRUE(same_bits(render_ok(scene, o).radiance, seen->radiance));
  }
}

// Le (1 + a + a^2 + a^3) at 3 bounces at every pixel from cameras the bake never knew (the bake has
// none).
TEST(AtlasFile, EnclosureFromTheFileIsExactFromSeveralCameras) {
  Dir dir;
  Scene s = furnace(false, 12, 9);
  const RenderOptions o = surface(4096, 16, 3);
  bake_ok(s, o, dir.file("f.exr"));
  RenderOptions view = o;
  view.surface.atlas = dir.file("f.exr");
  const double want = 1 + 0.6 + 0.36 + 0.216;
  for (const Camera& c : {s.camera, camera({-0.5f, 1, 1.5f}, {0.5f, -0.8f, -0.9f}, 12, 9, 100),
                          camera({0.8f, -0.9f, -0.8f}, {0, 0, 1}, 10, 10, 120)}) {
    s.camera = c;
    const ImageRgb img = render_ok(s, view).radiance;
    for (int y = 0; y < img.height(); ++y)
      for (int x = 0; x < img.width(); ++x) {
        ASSERT_NEAR(img.at(x, y).r, want, 1e-4 * want);
        ASSERT_NEAR(img.at(x, y).b, 0.25 * want, 1e-4 * want);
      }
  }
}

// The floor under the sphere light, seen through the file's atlas from above and from oblique
// eyes, reflects a Le (r/d)^2 cos(theta) to the error of the bake in memory (0.170 at these
// texels and maps, surface_cascades_test).
TEST(AtlasFile, FloorUnderASphereLightFromTheFile) {
  Dir dir;
  const Scene s = lamp_over_floor();
  bake_ok(s, surface(4096, 16), dir.file("lamp.exr"));
  atlas::Record r;
  Expected<atlas::Baked> b = atlas::read_atlas(dir.file("lamp.exr"), s, std::uint64_t(1) << 32, r);
  ASSERT_TRUE(b) << b.error().message;
  Expected<RayScene> rays = RayScene::build(s);
  ASSERT_TRUE(rays);
  const Vec3 light{0.2f, 1, -0.1f};
  for (const Vec3 eye : {Vec3{0, 3, 0}, Vec3{3, 1.5f, 0.5f}, Vec3{-2, 2, -2.5f}}) {
    double sum2 = 0, sum = 0;
    int n = 0;
    for (float z = -1.5f; z <= 1.5f; z += 0.1f)
      for (float x = -1.5f; x <= 1.5f; x += 0.1f) {
        if (x * x + z * z > 1.5f * 1.5f) continue;
        const Vec3 d = normalize(Vec3{x, 0, z} - eye);
        Hit h;
        if (!rays->intersect(Ray{eye, d}, h) || h.kind != ShapeKind::disk) continue;
        const Rgb l = albedo_at(s, h) * b->irradiance_at(s, *rays, h, -d) * float(1 / kPi);
        const double dx = light.x - h.position.x, dy = light.y, dz = light.z - h.position.z;
        const double d2 = dx * dx + dy * dy + dz * dz;
        const double want = 0.5 * 30 * 0.09 / d2 * (dy / std::sqrt(d2));
        sum2 += (l.g - want) * (l.g - want);
        sum += want;
        ++n;
      }
    ASSERT_GT(n, 200);
    const double e = std::sqrt(sum2 / n) / (sum / n);
    std::printf("atlas_file_test: floor from (%g, %g, %g): rel. RMSE %.4g\n", eye.x, eye.y, eye.z,
                e);
    EXPECT_LT(e, 0.20) << eye.x << " " << eye.y << " " << eye.z;
  }
}

// Cascade 0's radiance per direction: in the enclosure at 2 bounces every covered texel sees
// Le (1 + a) from every direction into the room, nothing from those out of it (16-bit floats:
// to 1e-3).
TEST(AtlasFile, HoldsCascadeZerosRadiancePerDirection) {
  Dir dir;
  const Scene s = furnace(false, 8, 6);
  bake_ok(s, surface(1024, 16, 2), dir.file("f.exr"));
  atlas::Record r;
  Expected<atlas::Baked> b = atlas::read_atlas(dir.file("f.exr"), s, std::uint64_t(1) << 32, r);
  ASSERT_TRUE(b) << b.error().message;
  EXPECT_EQ(r.directions, 16);
  EXPECT_EQ(r.bounces, 2);
  ASSERT_EQ(b->side0, 4);
  ASSERT_EQ(b->radiance.size(), b->texels.size() * 16);
  const std::vector<Vec3> dirs = octahedral::map_directions(4);
  std::size_t covered = 0;
  for (std::size_t k = 0; k < b->texels.size(); ++k) {
    if (b->texels[k].chart < 0) continue;
    ++covered;
    // Inside the room (the normal's side): the walls; outside: nothing (no sky).
    const Vec3 n = b->texels[k].normal;
    // The map lies in the chart's direction frame.
    const atlas::DirectionFrame f =
        atlas::direction_frame(b->atlas.charts[std::size_t(b->texels[k].chart)]);
    for (int d = 0; d < 16; ++d) {
      const Rgb v = b->radiance[k * 16 + std::size_t(d)];
      const float c = dot(f.to_world(dirs[std::size_t(d)]), n);
      if (std::abs(c) < 0.05f) continue;
      ASSERT_NEAR(v.r, c > 0 ? 1.6 : 0, 2e-3) << k << " " << d;
      ASSERT_NEAR(v.b, c > 0 ? 0.4 : 0, 1e-3) << k << " " << d;
    }
    // pi Le (1 + a) on the side the room is on.
    ASSERT_NEAR(b->front[k].r, kPi * 1.6, 1e-3);
  }
  EXPECT_GT(covered, 500u);
  // Without it: the irradiance only.
  Expected<BakeResult> plain = bake(s, surface(1024, 16, 2), dir.file("p.exr"), false);
  ASSERT_TRUE(plain);
  EXPECT_FALSE(plain->radiance);
  Expected<atlas::Baked> p = atlas::read_atlas(dir.file("p.exr"), s, std::uint64_t(1) << 32, r);
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_EQ(p->side0, 0);
  EXPECT_LT(std::filesystem::file_size(dir.file("p.exr")),
            std::filesystem::file_size(dir.file("f.exr")));
}

// What a view refuses, naming the file, with no image.
TEST(AtlasFile, RefusesAForeignDamagedOrMismatchedAtlas) {
  Dir dir;
  const Scene s = lamp_over_floor();
  const RenderOptions o = surface(1024, 16);
  const std::string good = dir.file("lamp.exr");
  bake_ok(s, o, good);
  auto refused = [&](const Scene& scene, const std::string& path, int bounces,
                     const std::string& words) {
    RenderOptions view = o;
    view.bounces = bounces;
    view.surface.atlas = path;
    const Expected<RenderResult> r = render(scene, view);
    ASSERT_FALSE(r) << words;
    EXPECT_EQ(r.error().message.rfind(path + ": ", 0), 0u) << r.error().message;
    EXPECT_NE(r.error().message.find(words), std::string::npos) << r.error().message;
  };
  // Another scene: the floor's albedo changed, or the light moved.
  Scene other = s;
  other.materials[0].albedo = {0.4f, 0.5f, 0.5f};
  refused(other, good, 1, "baked for another scene");
  other = s;
  other.spheres[0].center.x += 0.01f;
  refused(other, good, 1, "baked for another scene");
  // The same scene, another camera: accepted (the hash leaves the camera out).
  other = s;
  other.camera = camera({1, 1, 1}, {0, 0, 0}, 8, 8);
  EXPECT_EQ(atlas::scene_hash(other), atlas::scene_hash(s));
  // Other bounces.
  refused(s, good, 2, "baked with 1 bounce(s), asked for 2: pass --bounces 1");
  // Not an EXR; an EXR that is no atlas (a render's image).
  const std::string text = dir.write("text.exr", "not an image at all");
  refused(s, text, 1, "not an EXR file");
  const std::string image = dir.file("image.exr");
  ASSERT_TRUE(io::write_exr(image, ImageRgb(4, 4)));
  refused(s, image, 1, "not a Penumbra surface atlas");
  // Truncated: its first half.
  const std::string bytes = penumbra::testing::slurp(good);
  const std::string cut = dir.write("cut.exr", bytes.substr(0, bytes.size() / 2));
  refused(s, cut, 1, "EXR");
  // An attribute claiming more bytes than the file holds (OpenEXR would allocate them first: a
  // 2.4 KB file asked for 1.6 GB), and a channel list that does not end where its size says.
  {
    std::string damaged = bytes;
    const std::string key = std::string("penumbra.record") + '\0' + "string" + '\0';
    const std::size_t at = damaged.find(key);
    ASSERT_NE(at, std::string::npos);
    damaged.replace(at + key.size(), 4, std::string("\x00\x00\x02\x64", 4));
    refused(s, dir.write("huge.exr", damaged), 1,
            "damaged EXR header (attribute 'penumbra.record' claims 1677852672 bytes");
  }
  // The good file read, changed by `change`, written as `name`: its path.
  auto altered = [&](const std::string& name, const std::function<void(io::ExrChannels&)>& change) {
    Expected<io::ExrChannels> img = io::read_exr_channels(good);
    EXPECT_TRUE(img);
    if (!img) return std::string();
    change(*img);
    const std::string path = dir.file(name);
    Expected<io::StagedFile> staged = io::stage_exr_channels(path, *img);
    EXPECT_TRUE(staged && io::publish(*staged));
    return path;
  };
  auto without = [&](const std::string& channel) {
    return altered("missing.exr", [&](io::ExrChannels& img) {
      std::erase_if(img.channels, [&](const io::ExrChannel& c) { return c.name == channel; });
    });
  };
  // A value that cannot be light.
  const std::string nan = altered("nan.exr", [](io::ExrChannels& img) {
    for (io::ExrChannel& c : img.channels)
      if (c.name == "irradiance.front.G") {
        for (std::size_t k = 0; k < c.values.size(); ++k)
          if (c.values[k] > 0) {
            c.values[k] = std::numeric_limits<float>::quiet_NaN();
            break;
          }
      }
  });
  refused(s, nan, 1, "channel 'irradiance.front.G' holds nan");
  // A channel missing.
  refused(s, without("sun.back.B"), 1, "no channel 'sun.back.B'");
  refused(s, without("chart"), 1, "no channel 'chart'");
  // A radiance channel short of Q0's.
  atlas::Record record;
  const Expected<atlas::Baked> short_of =
      atlas::read_atlas(without("radiance.15.B"), s, std::uint64_t(1) << 32, record);
  ASSERT_FALSE(short_of);
  EXPECT_NE(short_of.error().message.find("47 radiance channels, expected 48"), std::string::npos)
      << short_of.error().message;
  // A chart list of the wrong types, a record out of range.
  for (const auto& [key, from, to, words] :
       {std::tuple<std::string, std::string, std::string, std::string>{
            "penumbra.charts",
            "\"height\":", "\"height\":\"x\",\"h\":", "are not the ones this build makes"},
        {"penumbra.charts", "[{", "[7,{", "a chart is no object"},
        {"penumbra.record", "\"directions\":16", "\"directions\":2147483647",
         "record is damaged"}}) {
    const std::string header = altered("header.exr", [&](io::ExrChannels& img) {
      for (auto& [name, value] : img.attributes)
        if (name == key) {
          ASSERT_NE(value.find(from), std::string::npos) << value;
          value.replace(value.find(from), from.size(), to);
        }
    });
    refused(s, header, 1, words);
  }
  // A bake refuses a path to read and a scene with fog, writing nothing.
  RenderOptions both = o;
  both.surface.atlas = good;
  EXPECT_FALSE(bake(s, both, dir.file("x.exr")));
  EXPECT_FALSE(bake(furnace(true, 8, 6), o, dir.file("x.exr")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("x.exr")));
}

}  // namespace
}  // namespace penumbra::spaceland
