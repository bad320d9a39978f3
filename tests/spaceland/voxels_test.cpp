// The voxel grid of the world-space probe grid: conservative surfaces (no ray through a wall one
// voxel thick, at any tilt), fog boxes as partial extinction (Beer-Lambert and emission in closed
// form), emitting surfaces seen through fog, the memory limit, and empty-space skipping (the
// distance field against a brute-force search, and marches that leap giving what a voxel at a
// time gives).
#include "spaceland/grid/voxels.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "spaceland/color.hpp"
#include "spaceland/scene_builders.hpp"

namespace penumbra::spaceland::grid {
namespace {

using namespace penumbra::spaceland::testing;

constexpr std::uint64_t kGiB = std::uint64_t(1) << 30;

// A square wall of zero thickness through the origin with normal n, 2 across, emitting Le.
Scene thin_wall(Vec3 n, Rgb le) {
  Scene s;
  const std::uint32_t m = add_material(s, {0.5f, 0.5f, 0.5f}, le);
  n = normalize(n);
  const Vec3 u = normalize(cross(n, std::abs(n.x) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0}));
  const Vec3 w = cross(n, u);
  TriangleMesh mesh;
  mesh.positions = {u * -1 + w * -1, u * 1 + w * -1, u * 1 + w * 1, u * -1 + w * 1};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  mesh.materials = {m, m};
  mesh.object = add_object(s, "wall");
  s.meshes.push_back(mesh);
  return s;
}

TEST(Voxels, NoRayCrossesAWallOneVoxelThickAtAnyTilt) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1, 1);
  for (Vec3 n : {Vec3{0, 0, 1}, Vec3{1, 1, 0}, Vec3{0.3f, -0.5f, 0.8f}, Vec3{1, 2, 3}}) {
    const Scene s = thin_wall(n, {2, 1, 0.5f});
    const Expected<Voxels> v = voxelise(s, 0.1f, kGiB);
    ASSERT_TRUE(v.ok()) << v.error().message;
    const Vec3 nn = normalize(n);
    int blocked = 0;
    for (int i = 0; i < 2000; ++i) {
      // From a point 0.5 in front of the wall's inner part to one 0.5 behind it.
      const Vec3 on = Vec3{u(rng), u(rng), u(rng)} * 0.4f;
      const Vec3 a = on - nn * dot(on, nn) + nn * 0.5f + Vec3{u(rng), u(rng), u(rng)} * 0.3f;
      const Vec3 b = on - nn * dot(on, nn) - nn * 0.5f + Vec3{u(rng), u(rng), u(rng)} * 0.3f;
      const Vec3 d = b - a;
      const float len = length(d);
      const Segment seg = march(*v, a, d * (1 / len), 0, len);
      blocked += seg.blocked;
      // What the wall's voxel gives: its emission, nothing behind it.
      if (seg.blocked) {
        EXPECT_NEAR(seg.radiance.r, 2.0f, 1e-5f);
        EXPECT_EQ(seg.transmittance.g, 0.0f);
      }
    }
    EXPECT_EQ(blocked, 2000) << n.x << " " << n.y << " " << n.z;
  }
}

// A fog box aligned with the voxels, and one half a voxel off: Beer-Lambert and the fog's own
// emission along an axis, against the closed forms.
TEST(Voxels, FogIsBeerLambertWithEmissionInClosedForm) {
  for (float offset : {0.0f, 0.05f}) {
    Scene s;
    Medium m;
    m.center = {offset, 0, 0};
    m.half_size = {1, 0.5f, 0.5f};
    m.extinction = {0.5f, 1, 2};
    m.albedo = {0.3f, 0.3f, 0.3f};
    m.emission = {1, 2, 3};
    s.media.push_back(m);
    const Expected<Voxels> v = voxelise(s, 0.1f, kGiB);
    ASSERT_TRUE(v.ok()) << v.error().message;
    // Along x through the box's middle: 2 units of fog.
    const Segment seg = march(*v, {-5, 0.01f, 0.02f}, {1, 0, 0}, 0, 10);
    EXPECT_FALSE(seg.blocked);
    const float sigma[3] = {0.5f, 1, 2}, e[3] = {1, 2, 3};
    for (int c = 0; c < 3; ++c) {
      const double t = std::exp(-2.0 * sigma[c]);
      EXPECT_NEAR(channel(seg.transmittance, c), t, 1e-5 * (1 + t)) << c << " offset " << offset;
      EXPECT_NEAR(channel(seg.radiance, c), e[c] * (1 - t) / sigma[c], 2e-5) << c;
    }
    // The albedo is the box's, where the box covers a voxel at all.
    const std::size_t k = v->index(v->nx / 2, v->ny / 2, v->nz / 2);
    EXPECT_NEAR(v->albedo[k].r, 0.3f, 1e-6f);
  }
}

// Hundreds of overlapping fog boxes, along the axes and turned: each voxel's extinction and
// emission are the sum over the boxes of their coefficients times the fraction they cover,
// computed here voxel by voxel and box by box (an axis-aligned box's exact overlap, a turned
// one's 4^3 points), as the row-by-row voxelisation with its difference arrays must give. It
// used to cost every box's volume times 64 points (5,000 boxes of 1-4 units: 12 s, now 0.8 s).
TEST(Voxels, ManyFogBoxesAddUpVoxelByVoxel) {
  Scene s;
  std::mt19937 rng(37);
  std::uniform_real_distribution<float> u(0, 1);
  for (int i = 0; i < 300; ++i) {
    Medium m;
    m.center = {u(rng) * 4 - 2, u(rng) * 2 - 1, u(rng) * 4 - 2};
    m.half_size = {0.05f + u(rng), 0.05f + u(rng) * 0.5f, 0.05f + u(rng)};
    if (i % 3 == 0) {  // turned about y by an angle
      const float a = u(rng) * 1.5f;
      m.axes = {Vec3{std::cos(a), 0, -std::sin(a)}, Vec3{0, 1, 0},
                Vec3{std::sin(a), 0, std::cos(a)}};
    }
    m.extinction = {u(rng), u(rng) * 2, 0.5f};
    m.albedo = {0.5f, 0.5f, 0.5f};
    m.emission = {u(rng) * 0.1f, 0, 0.2f};
    s.media.push_back(m);
  }
  const Expected<Voxels> built = voxelise(s, 0.1f, kGiB);
  ASSERT_TRUE(built.ok()) << built.error().message;
  const Voxels& v = *built;
  std::size_t checked = 0, wrong = 0;
  for (int z = 0; z < v.nz; z += 3)
    for (int y = 0; y < v.ny; y += 2)
      for (int x = 0; x < v.nx; ++x) {
        const Vec3 lo = v.origin + Vec3{float(x), float(y), float(z)} * v.size;
        double ext = 0, emis = 0;
        for (const Medium& m : s.media) {
          double f = 0;
          if (m.axes[0].x == 1) {
            f = 1;
            for (int k = 0; k < 3; ++k)
              f *= std::max(0.0,
                            std::min(double(lo[k]) + v.size, double(m.center[k]) + m.half_size[k]) -
                                std::max(double(lo[k]), double(m.center[k]) - m.half_size[k])) /
                   v.size;
          } else {
            int in = 0;
            for (int i = 0; i < 64; ++i) {
              const Vec3 p =
                  lo +
                  Vec3{(float(i % 4) + 0.5f) / 4 * v.size, (float(i / 4 % 4) + 0.5f) / 4 * v.size,
                       (float(i / 16) + 0.5f) / 4 * v.size} -
                  m.center;
              bool inside = true;
              for (int j = 0; j < 3; ++j)
                inside = inside && std::abs(dot(p, m.axes[std::size_t(j)])) <= m.half_size[j];
              in += inside;
            }
            f = in / 64.0;
          }
          ext += f * m.extinction.g;
          emis += f * m.emission.b;
        }
        const std::size_t k = v.index(x, y, z);
        ++checked;
        const bool ok = std::abs(v.extinction[k].g - ext) <= 1e-5 * (1 + ext) &&
                        std::abs(v.emission[k].b - emis) <= 1e-5 * (1 + emis) &&
                        v.extinction[k].g >= 0;
        wrong += !ok;
        if (!ok && wrong < 5)
          ADD_FAILURE() << "voxel " << x << " " << y << " " << z << ": extinction "
                        << v.extinction[k].g << " want " << ext << ", emission " << v.emission[k].b
                        << " want " << emis;
      }
  EXPECT_GT(checked, 10000u);
  EXPECT_EQ(wrong, 0u);
}

// An emitting wall behind a fog slab: its radiance arrives times the slab's transmittance.
TEST(Voxels, AnEmittingWallIsSeenThroughTheFog) {
  Scene s = thin_wall({1, 0, 0}, {4, 4, 4});
  for (Vec3& p : s.meshes[0].positions) p.x += 3;  // the wall at x = 3
  Medium m;
  m.center = {0, 0, 0};
  m.half_size = {1, 2, 2};
  m.extinction = {1, 1, 1};
  s.media.push_back(m);
  const Expected<Voxels> v = voxelise(s, 0.1f, kGiB);
  ASSERT_TRUE(v.ok()) << v.error().message;
  const Segment seg = march(*v, {-3, 0.03f, 0.01f}, {1, 0, 0}, 0, 100);
  ASSERT_TRUE(seg.blocked);
  EXPECT_NEAR(seg.radiance.r, 4 * std::exp(-2.0), 1e-4);
  // The wall's voxel starts within a voxel before the wall.
  EXPECT_NEAR(seg.t_end, 6.0f, 0.1f + 1e-4f);
  EXPECT_GE(seg.t_end, 5.9f - 1e-4f);
}

// Spheres and disks are rasterised as shells and as their plane within the radius.
TEST(Voxels, SpheresAndDisksBlockWhatCrossesThem) {
  Scene s;
  const std::uint32_t m = add_material(s, {0.2f, 0.4f, 0.6f});
  s.spheres.push_back({{0, 0, 0}, 1, m, add_object(s, "sphere")});
  Disk d;
  d.center = {0, 0, 3};
  d.normal = normalize(Vec3{0, 1, 1});
  d.radius = 0.8f;
  d.material = m;
  d.object = add_object(s, "disk");
  s.disks.push_back(d);
  const Expected<Voxels> v = voxelise(s, 0.05f, kGiB);
  ASSERT_TRUE(v.ok()) << v.error().message;
  // Through the sphere's centre: blocked at its shell, within a voxel diagonal of r = 1.
  const Segment a = march(*v, {-3, 0.01f, 0.02f}, {1, 0, 0}, 0, 6);
  ASSERT_TRUE(a.blocked);
  EXPECT_NEAR(a.t_end, 2.0f, 0.05f * std::sqrt(3.0f) + 1e-4f);
  // The sphere's inside is not filled: from its centre a ray leaves through the shell.
  const Segment inside = march(*v, {0, 0, 0}, {0, 1, 0}, 0, 3);
  ASSERT_TRUE(inside.blocked);
  EXPECT_GT(inside.t_end, 0.9f);
  // The disk: blocked through its middle, free beside it.
  EXPECT_TRUE(march(*v, {0, -2, 3}, {0, 1, 0}, 0, 4).blocked);
  EXPECT_FALSE(march(*v, {1.2f, -2, 3}, {0, 1, 0}, 0, 4).blocked);
  const std::size_t k =
      v->index(int((0.98f - v->origin.x) / v->size), int((0.01f - v->origin.y) / v->size),
               int((0.01f - v->origin.z) / v->size));
  ASSERT_TRUE(v->opaque(k));
  EXPECT_NEAR(v->albedo[k].g, 0.4f, 1e-6f);
}

// A mesh's zero-area triangle (collinear corners, as meshes from files hold) covers nothing: its
// voxels stay free, while a real triangle beside it blocks.
TEST(Voxels, AZeroAreaTriangleStopsNoLight) {
  Scene s = thin_wall({0, 0, 1}, {});
  TriangleMesh& mesh = s.meshes[0];
  const std::uint32_t first = std::uint32_t(mesh.positions.size());
  mesh.positions.push_back({-0.8f, 0.5f, 0.5f});
  mesh.positions.push_back({0.0f, 0.5f, 0.5f});
  mesh.positions.push_back({0.8f, 0.5f, 0.5f});
  mesh.triangles.push_back({first, first + 1, first + 2});
  mesh.materials.push_back(mesh.materials[0]);
  // And one along a diagonal, its corners on one line but for the floats' rounding.
  const Vec3 a{-0.8f, 0.1f, 0.3f}, d{0.1f, 0.03f, 0.07f};
  mesh.positions.push_back(a);
  mesh.positions.push_back(a + d * 3);
  mesh.positions.push_back(a + d * 7);
  mesh.triangles.push_back({first + 3, first + 4, first + 5});
  mesh.materials.push_back(mesh.materials[0]);
  const Expected<Voxels> v = voxelise(s, 0.05f, kGiB);
  ASSERT_TRUE(v.ok()) << v.error().message;
  EXPECT_FALSE(march(*v, {0.01f, 0.51f, 1}, {0, 0, -1}, 0, 0.9f).blocked);
  EXPECT_TRUE(march(*v, {0.01f, 0.51f, 1}, {0, 0, -1}, 0, 2).blocked);
  for (float t : {3.5f, 5.0f, 6.5f}) {
    const Vec3 p = a + d * t;
    EXPECT_FALSE(march(*v, p + Vec3{0, 0, 0.3f}, {0, 0, -1}, 0, 0.6f).blocked) << t;
  }
}

TEST(Voxels, SizesAndTheMemoryLimit) {
  const Scene s = thin_wall({0, 0, 1}, {1, 1, 1});
  const Expected<Voxels> v = voxelise(s, 0.25f, kGiB);
  ASSERT_TRUE(v.ok());
  // The wall spans [-1, 1]^2 x {0}: 8 voxels and the padding each side; none but the padding
  // along z.
  EXPECT_EQ(v->nx, 8 + 2 * kPadding);
  EXPECT_EQ(v->ny, 8 + 2 * kPadding);
  EXPECT_EQ(v->nz, 2 * kPadding);
  EXPECT_EQ(voxel_bytes(v->count()), v->count() * 37);
  EXPECT_EQ(voxel_bytes(v->count(), true), v->count() * 87);
  // The default: the longest side over 128, unless that passes the limit.
  EXPECT_NEAR(default_voxel_size(s, kGiB), 2.0f / 128, 1e-6f);
  EXPECT_GT(default_voxel_size(s, 1 << 16), 2.0f / 128 * 4);
  const std::uint64_t small = 1 << 16;
  const Expected<Voxels> fits = voxelise(s, default_voxel_size(s, small), small);
  EXPECT_TRUE(fits.ok());
  const Expected<Voxels> big = voxelise(s, 0.001f, small);
  ASSERT_FALSE(big.ok());
  EXPECT_NE(big.error().message.find("max_memory"), std::string::npos) << big.error().message;
  for (float bad : {0.0f, -1.0f, std::nanf("")}) {
    const Expected<Voxels> r = voxelise(s, bad, kGiB);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("`grid.voxel`"), std::string::npos);
  }
}

// A room with a sphere, a box and fog in it: the distance field is the chessboard distance to the
// nearest voxel with something in it (brute force here), and 20000 marches with it give what a
// march a voxel at a time gives, bit for bit, from the same voxel (each surface voxel shows its own
// light): from random points in random directions and from voxel centres towards others (rays along
// voxel edges and through their corners).
TEST(Voxels, EmptySpaceSkippingChangesNothing) {
  Scene s;
  add_box(s, {-2, -1, -2}, {2, 1.5f, 2}, add_material(s, {0.5f, 0.5f, 0.5f}, {0.2f, 0.1f, 0}));
  add_box(s, {-0.5f, -1, -0.3f}, {0.2f, 0.2f, 0.4f}, add_material(s, {0.5f, 0.5f, 0.5f}));
  add_sphere(s, {1, 0.5f, 1}, 0.3f, add_material(s, {0, 0, 0}, {5, 5, 5}));
  Medium m;
  m.center = {-1, 0.8f, 1};
  m.half_size = {0.5f, 0.3f, 0.6f};
  m.extinction = {0.5f, 1, 2};
  m.emission = {0.1f, 0.2f, 0.3f};
  s.media.push_back(m);
  Expected<Voxels> built = voxelise(s, 0.1f, kGiB);
  ASSERT_TRUE(built.ok());
  // Each surface voxel its own light, so that a march meeting another voxel shows.
  for (std::size_t k = 0; k < built->emission.size(); ++k)
    if (built->opaque(k)) built->emission[k] = {float(k % 97) + 1, float(k % 89), 1};
  const Voxels& v = *built;
  ASSERT_EQ(v.skip.size(), v.count());
  std::vector<int> full;
  for (int z = 0; z < v.nz; ++z)
    for (int y = 0; y < v.ny; ++y)
      for (int x = 0; x < v.nx; ++x) {
        const std::size_t k = v.index(x, y, z);
        if (!is_black(v.extinction[k]) || !is_black(v.emission[k]))
          full.insert(full.end(), {x, y, z});
      }
  std::mt19937 rng(11);
  for (int i = 0; i < 300; ++i) {
    const int x = int(rng() % unsigned(v.nx)), y = int(rng() % unsigned(v.ny)),
              z = int(rng() % unsigned(v.nz));
    int best = 255;
    for (std::size_t j = 0; j < full.size(); j += 3)
      best = std::min(best, std::max({std::abs(full[j] - x), std::abs(full[j + 1] - y),
                                      std::abs(full[j + 2] - z)}));
    EXPECT_EQ(int(v.skip[v.index(x, y, z)]), best) << x << " " << y << " " << z;
  }
  Voxels plain = v;
  plain.skip.clear();
  std::uniform_real_distribution<float> u(-2.5f, 2.5f);
  int ended = 0;
  for (int i = 0; i < 20000; ++i) {
    Vec3 o{u(rng), u(rng), u(rng)}, d = normalize(Vec3{u(rng), u(rng), u(rng)});
    if (i % 2) {
      const int c[3] = {int(rng() % unsigned(v.nx)), int(rng() % unsigned(v.ny)),
                        int(rng() % unsigned(v.nz))};
      o = v.centre(c[0], c[1], c[2]);
      const Vec3 to = v.centre(c[0] + int(rng() % 9) - 4, c[1] + int(rng() % 9) - 4,
                               c[2] + int(rng() % 9) - 4) -
                      o;
      if (!(length(to) > 0)) continue;
      d = normalize(to);
    }
    const float tmin = i % 3 == 0 ? 0.4f : 0.0f, tmax = i % 4 < 2 ? 3.0f : 1e30f;
    const Segment a = march(v, o, d, tmin, tmax), b = march(plain, o, d, tmin, tmax);
    // The same bits: the leaps and the walk place voxel boundaries by one expression.
    ASSERT_EQ(a.blocked, b.blocked) << i;
    EXPECT_EQ(a.t_end, b.t_end) << i;
    EXPECT_EQ(a.radiance.r, b.radiance.r) << i;
    EXPECT_EQ(a.radiance.g, b.radiance.g) << i;
    EXPECT_EQ(a.radiance.b, b.radiance.b) << i;
    EXPECT_EQ(a.transmittance.b, b.transmittance.b) << i;
    ended += a.blocked;
  }
  EXPECT_GT(ended, 1000);  // many end on a surface voxel, after leaps
}

// A wall one voxel thick holding a value per side: a ray travelling +x sees the - side's value,
// one travelling -x the + side's, one along the wall either (it enters through another face).
TEST(Voxels, AThinWallShowsTheSideARayComesFrom) {
  const Scene s = thin_wall({1, 0, 0}, {1, 1, 1});
  Expected<Voxels> v = voxelise(s, 0.3f, kGiB);  // x = 0 lies inside a voxel: one voxel thick
  ASSERT_TRUE(v.ok());
  v->thin.assign(v->emission.size(), 0);
  v->emission_minus = v->emission;
  for (std::size_t k = 0; k < v->emission.size(); ++k)
    if (v->opaque(k)) {
      v->thin[k] = 1;  // thin along x
      v->emission[k] = {5, 0, 0};
      v->emission_minus[k] = {0, 0, 7};
    }
  const Segment from_minus = march(*v, {-1, 0.1f, 0.05f}, {1, 0, 0}, 0, 2);
  const Segment from_plus = march(*v, {1, 0.1f, 0.05f}, {-1, 0, 0}, 0, 2);
  ASSERT_TRUE(from_minus.blocked && from_plus.blocked);
  EXPECT_EQ(from_minus.radiance.b, 7.0f);
  EXPECT_EQ(from_minus.radiance.r, 0.0f);
  EXPECT_EQ(from_plus.radiance.r, 5.0f);
  EXPECT_EQ(from_plus.radiance.b, 0.0f);
}

}  // namespace
}  // namespace penumbra::spaceland::grid
