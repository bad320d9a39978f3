// RayScene: Embree's answers against closed forms, and the offsets that keep rays off their own
// surface.
#include "spaceland/embree/ray_scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <thread>
#include <vector>

namespace penumbra::spaceland {
namespace {

RayScene build_ok(const Scene& s) {
  Expected<RayScene> r = RayScene::build(s);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  if (!r.ok()) std::abort();
  return std::move(r).value();
}

// The parallelogram corner + s u + t v as two triangles (corner, +u, +u+v) and (corner, +u+v, +v).
TriangleMesh quad(Vec3 corner, Vec3 u, Vec3 v, std::uint32_t material = 0, int object = -1) {
  TriangleMesh m;
  m.positions = {corner, corner + u, corner + u + v, corner + v};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.materials = {material, material};
  m.object = object;
  return m;
}

// Closed-form nearest positive root of |o + t d - c|^2 = r^2, in double; -1 on a miss.
double sphere_t(Vec3 o, Vec3 d, Vec3 c, double r) {
  const double ox = double(o.x) - c.x, oy = double(o.y) - c.y, oz = double(o.z) - c.z;
  const double a = double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z;
  const double b = ox * d.x + oy * d.y + oz * d.z;
  const double cc = ox * ox + oy * oy + oz * oz - r * r;
  const double disc = b * b - a * cc;
  if (disc < 0) return -1;
  const double t0 = (-b - std::sqrt(disc)) / a, t1 = (-b + std::sqrt(disc)) / a;
  return t0 > 0 ? t0 : t1 > 0 ? t1 : -1;
}

void expect_near(Vec3 a, Vec3 b, float tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<float> g;
  return normalize(Vec3{g(rng), g(rng), g(rng)});
}

TEST(RaySceneSphere, DistanceAndNormalMatchTheClosedForm) {
  for (Vec3 c : {Vec3{0.5f, -1, 2}, Vec3{480, 300, -520}}) {
    Scene s;
    const float r = 1.5f;
    s.spheres.push_back({c, r, 3, 7});
    const RayScene rs = build_ok(s);
    std::mt19937 rng(1);
    for (int i = 0; i < 200; ++i) {
      // Half the rays start outside towards a point near the centre, half inside (two-sided).
      const bool inside = i % 2;
      const Vec3 o = c + random_unit(rng) * (inside ? 0.9f * r : 6 * r);
      const Vec3 d = (c + random_unit(rng) * (0.8f * r) - o) * 0.37f;
      const double t = sphere_t(o, d, c, r);
      ASSERT_GT(t, 0);
      Hit h;
      ASSERT_TRUE(rs.intersect(Ray{o, d}, h));
      EXPECT_NEAR(h.t, t, 1e-4 * t) << i;
      const Vec3 p{float(o.x + t * d.x), float(o.y + t * d.y), float(o.z + t * d.z)};
      expect_near(h.position, p, 1e-4f * (std::abs(c.x) + r));
      EXPECT_NEAR(length(h.position - c), r, 1e-6f * (std::abs(c.x) + r));
      expect_near(h.geometric_normal, (p - c) / r, 1e-4f);
      EXPECT_EQ(h.shading_normal, h.geometric_normal);
      EXPECT_EQ(h.kind, ShapeKind::sphere);
      EXPECT_EQ(h.material, 3u);
      EXPECT_EQ(h.object, 7);
    }
    // A ray passing just outside the radius misses.
    Hit h;
    EXPECT_FALSE(rs.intersect(Ray{c + Vec3{-10, r * 1.001f, 0}, Vec3{1, 0, 0}}, h));
    EXPECT_TRUE(rs.intersect(Ray{c + Vec3{-10, r * 0.999f, 0}, Vec3{1, 0, 0}}, h));
  }
}

TEST(RaySceneDisk, HitsInsideTheRadiusFromBothSides) {
  Scene s;
  const Vec3 n = normalize(Vec3{0.3f, 1, -0.2f});
  s.disks.push_back({Vec3{1, 2, 3}, n, 2, 5, 9});
  const RayScene rs = build_ok(s);
  // In-plane directions perpendicular to n.
  const Vec3 a = normalize(cross(n, Vec3{1, 0, 0})), b = cross(n, a);
  for (float side : {1.0f, -1.0f}) {  // from above and from below: two-sided
    for (int k = 0; k < 16; ++k) {
      const float ang = 0.4f * k;
      const Vec3 e = a * std::cos(ang) + b * std::sin(ang);
      const Vec3 d = -side * n + 0.2f * e;
      for (float rr : {0.0f, 1.0f, 1.99f, 2.01f}) {
        const Vec3 target = Vec3{1, 2, 3} + rr * e;
        const Vec3 o = target - 3 * d;
        Hit h;
        const bool hit = rs.intersect(Ray{o, d}, h);
        EXPECT_EQ(hit, rr < 2) << rr << " side " << side;
        if (!hit) continue;
        EXPECT_NEAR(h.t, 3, 1e-5);
        expect_near(h.position, target, 1e-5f);
        EXPECT_NEAR(dot(h.position - Vec3{1, 2, 3}, n), 0, 1e-6f);
        EXPECT_EQ(h.geometric_normal, n);  // as the disk is oriented, not turned to the ray
        EXPECT_EQ(h.shading_normal, n);
        EXPECT_EQ(h.kind, ShapeKind::disk);
        EXPECT_EQ(h.material, 5u);
        EXPECT_EQ(h.object, 9);
      }
    }
  }
}

TEST(RaySceneTriangle, BarycentricUvsAndInterpolatedNormals) {
  Scene s;
  TriangleMesh m;
  const Vec3 p0{0, 0, 0}, p1{2, 0, 0.5f}, p2{0.3f, 1.5f, 0};
  m.positions = {p0, p1, p2};
  m.normals = {normalize(Vec3{0, 0, 1}), normalize(Vec3{1, 0, 1}), normalize(Vec3{0, 1, 1})};
  m.uvs = {{0, 0}, {1, 0.25f}, {0.5f, 1}};
  m.triangles = {{0, 1, 2}};
  m.materials = {4};
  s.meshes.push_back(m);
  const RayScene rs = build_ok(s);
  const Vec3 ng = normalize(cross(p1 - p0, p2 - p0));
  for (auto [b1, b2] : {std::pair{0.2f, 0.3f}, {0.6f, 0.1f}, {0.05f, 0.9f}, {1 / 3.0f, 1 / 3.0f}}) {
    const float b0 = 1 - b1 - b2;
    const Vec3 p = b0 * p0 + b1 * p1 + b2 * p2;
    for (float side : {1.0f, -1.0f}) {
      Hit h;
      ASSERT_TRUE(rs.intersect(Ray{p + side * 2 * ng + Vec3{0.1f, 0, 0}, -side * ng}, h));
      const Vec3 q = p + Vec3{0.1f, 0, 0} - dot(Vec3{0.1f, 0, 0}, ng) * ng;  // the hit, exactly
      expect_near(h.position, q, 1e-5f);
      EXPECT_NEAR(h.t, 2 + side * dot(Vec3{0.1f, 0, 0}, ng), 1e-5);
      // Barycentrics of q (the ray is offset along x).
      const Vec3 e1 = p1 - p0, e2 = p2 - p0, w = q - p0;
      const float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
      const float den = d11 * d22 - d12 * d12;
      const float c1 = (d22 * dot(w, e1) - d12 * dot(w, e2)) / den;
      const float c2 = (d11 * dot(w, e2) - d12 * dot(w, e1)) / den;
      const float c0 = 1 - c1 - c2;
      EXPECT_NEAR(h.u, c0 * 0 + c1 * 1 + c2 * 0.5f, 1e-5f);
      EXPECT_NEAR(h.v, c0 * 0 + c1 * 0.25f + c2 * 1, 1e-5f);
      expect_near(h.shading_normal,
                  normalize(c0 * m.normals[0] + c1 * m.normals[1] + c2 * m.normals[2]), 1e-5f);
      // cross(p1 - p0, p2 - p0), whichever side the ray came from.
      expect_near(h.geometric_normal, ng, 1e-6f);
      EXPECT_EQ(h.material, 4u);
    }
  }
}

TEST(RaySceneTriangle, FlatMeshHasGeometricShadingNormalAndZeroUv) {
  Scene s;
  s.meshes.push_back(quad({0, 0, 0}, {0, 0, 1}, {1, 0, 0}));  // cross(u, v) = +y
  const RayScene rs = build_ok(s);
  Hit h;
  ASSERT_TRUE(rs.intersect(Ray{{0.3f, 1, 0.6f}, {0, -1, 0}}, h));
  EXPECT_EQ(h.geometric_normal, (Vec3{0, 1, 0}));
  EXPECT_EQ(h.shading_normal, (Vec3{0, 1, 0}));
  EXPECT_EQ(h.u, 0);
  EXPECT_EQ(h.v, 0);
}

TEST(RaySceneTriangle, QuadHasNoCrackAlongItsDiagonal) {
  for (float scale : {0.01f, 1.0f, 500.0f}) {
    Scene s;
    s.meshes.push_back(quad(Vec3{-0.3f, 0.2f, 0.7f} * scale, Vec3{1.3f, 0.1f, 0} * scale,
                            Vec3{0.2f, 0.1f, 1.1f} * scale));
    const RayScene rs = build_ok(s);
    const Vec3 a = s.meshes[0].positions[0], c = s.meshes[0].positions[2];
    std::mt19937 rng(2);
    int misses = 0;
    for (int i = 0; i < 20000; ++i) {
      const float f = (i + 0.5f) / 20000;
      const Vec3 target = a + f * (c - a);
      const Vec3 o = target + random_unit(rng) * scale;
      Hit h;
      if (!rs.intersect(Ray{o, target - o}, h)) ++misses;
    }
    EXPECT_EQ(misses, 0) << "scale " << scale;
  }
}

// A few meshes, spheres and disks for the random-ray tests.
Scene mixed_scene() {
  Scene s;
  s.meshes.push_back(quad({-2, 0, -2}, {4, 0, 0}, {0, 0, 4}, 0, 0));
  s.meshes.push_back(quad({-1, 0.5f, -1}, {0, 1, 0}, {0.5f, 0, 1}, 1, 1));
  s.meshes.push_back(quad({0.5f, 0.2f, 0}, {0.7f, 0.3f, 0.1f}, {0, 0.4f, 0.9f}, 2, 2));
  s.spheres.push_back({{0.5f, 1, 0.5f}, 0.4f, 3, 3});
  s.spheres.push_back({{-0.7f, 0.3f, 1.2f}, 0.3f, 4, 4});
  s.disks.push_back({{0, 1.8f, 0}, {0, -1, 0}, 0.6f, 5, 5});
  s.disks.push_back({{1.2f, 0.8f, -1}, normalize(Vec3{1, 1, 0}), 0.5f, 6, 6});
  return s;
}

std::vector<Ray> random_rays(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-2.5f, 2.5f);
  std::vector<Ray> rays;
  for (int i = 0; i < n; ++i) {
    Ray r{{u(rng), u(rng) + 1, u(rng)}, random_unit(rng) * (0.5f + (u(rng) + 2.5f))};
    if (i % 3 == 0) r.tmax = 0.7f;
    rays.push_back(r);
  }
  return rays;
}

TEST(RayScene, OccludedAgreesWithIntersect) {
  const RayScene rs = build_ok(mixed_scene());
  int hits = 0;
  for (const Ray& r : random_rays(5000, 3)) {
    Hit h;
    const bool hit = rs.intersect(r, h);
    hits += hit;
    EXPECT_EQ(hit, rs.occluded(r));
  }
  EXPECT_GT(hits, 500);  // the test means something
  EXPECT_LT(hits, 4500);
}

TEST(RayScene, RespectsTminAndTmax) {
  Scene s;
  s.meshes.push_back(quad({-1, 0, -1}, {0, 0, 2}, {2, 0, 0}));
  s.meshes.push_back(quad({-1, 2, -1}, {0, 0, 2}, {2, 0, 0}));
  const RayScene rs = build_ok(s);
  const Vec3 o{0.1f, 3, 0.2f}, d{0, -0.5f, 0};  // the planes at t = 2 and t = 6
  Hit h;
  ASSERT_TRUE(rs.intersect(Ray{o, d}, h));
  EXPECT_NEAR(h.t, 2, 1e-6);
  EXPECT_EQ(h.shape, 1u);
  ASSERT_TRUE(rs.intersect(Ray{o, d, 2.1f}, h));
  EXPECT_NEAR(h.t, 6, 1e-6);
  EXPECT_EQ(h.shape, 0u);
  EXPECT_FALSE(rs.intersect(Ray{o, d, 6.1f}, h));
  EXPECT_FALSE(rs.intersect(Ray{o, d, 0, 1.9f}, h));
  EXPECT_FALSE(rs.occluded(Ray{o, d, 0, 1.9f}));
  EXPECT_FALSE(rs.occluded(Ray{o, d, 2.1f, 5.9f}));
  EXPECT_TRUE(rs.occluded(Ray{o, d, 2.1f, 6.1f}));
}

TEST(RayScene, ReportsMaterialObjectShapeAndPrimitive) {
  Scene s;
  s.meshes.push_back(quad({-1, 0, -1}, {0, 0, 2}, {2, 0, 0}, 0, 0));
  TriangleMesh m = quad({-1, 1, -1}, {0, 0, 2}, {2, 0, 0}, 0, 4);
  m.materials = {7, 8};
  s.meshes.push_back(m);
  s.spheres.push_back({{5, 0, 0}, 0.5f, 1, 1});
  s.spheres.push_back({{8, 0, 0}, 0.5f, 2, 2});
  s.disks.push_back({{0, 0, 5}, {0, 0, 1}, 0.5f, 3, 3});
  s.disks.push_back({{0, 0, 8}, {0, 0, 1}, 0.5f, 9, 5});
  const RayScene rs = build_ok(s);
  struct Case {
    Ray ray;
    ShapeKind kind;
    std::uint32_t shape, primitive, material;
    int object;
  };
  // Triangle 0 of the quad is (corner, +u, +u+v): the side z > x here.
  const Case cases[] = {
      {{{-0.5f, 2, 0.5f}, {0, -1, 0}}, ShapeKind::triangle, 1, 0, 7, 4},
      {{{0.5f, 2, -0.5f}, {0, -1, 0}}, ShapeKind::triangle, 1, 1, 8, 4},
      {{{0.5f, 0.5f, -0.5f}, {0, -1, 0}}, ShapeKind::triangle, 0, 1, 0, 0},
      {{{5, 3, 0}, {0, -1, 0}}, ShapeKind::sphere, 0, 0, 1, 1},
      {{{8, 3, 0}, {0, -1, 0}}, ShapeKind::sphere, 1, 0, 2, 2},
      {{{0, 3, 5}, {0, -1, 0.001f}}, ShapeKind::disk, 0, 0, 3, 3},
      {{{0, 0.1f, 10}, {0, 0, -1}}, ShapeKind::disk, 1, 0, 9, 5},
  };
  for (const Case& c : cases) {
    Hit h;
    if (c.kind == ShapeKind::disk && c.shape == 0) {
      // A ray in the disk's plane would be degenerate: aim through it instead.
      ASSERT_TRUE(rs.intersect(Ray{{0.1f, 0.1f, 6}, {0, 0, -1}}, h));
    } else {
      ASSERT_TRUE(rs.intersect(c.ray, h));
    }
    EXPECT_EQ(h.kind, c.kind);
    EXPECT_EQ(h.shape, c.shape);
    EXPECT_EQ(h.primitive, c.primitive);
    EXPECT_EQ(h.material, c.material);
    EXPECT_EQ(h.object, c.object);
  }
}

void expect_same(const Hit& a, const Hit& b) {
  EXPECT_EQ(a.t, b.t);
  EXPECT_EQ(a.position, b.position);
  EXPECT_EQ(a.geometric_normal, b.geometric_normal);
  EXPECT_EQ(a.shading_normal, b.shading_normal);
  EXPECT_EQ(a.u, b.u);
  EXPECT_EQ(a.v, b.v);
  EXPECT_EQ(a.material, b.material);
  EXPECT_EQ(a.object, b.object);
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.shape, b.shape);
  EXPECT_EQ(a.primitive, b.primitive);
}

TEST(RayScene, StreamsEqualSingleRays) {
  const RayScene rs = build_ok(mixed_scene());
  const std::vector<Ray> rays = random_rays(3000, 4);
  std::vector<Hit> hits(rays.size());
  std::vector<std::uint8_t> found(rays.size()), blocked(rays.size());
  rs.occluded(rays, blocked);
  for (bool coherent : {false, true}) {
    rs.intersect(rays, hits, found, coherent);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      Hit h;
      ASSERT_EQ(bool(found[i]), rs.intersect(rays[i], h));
      ASSERT_EQ(bool(blocked[i]), rs.occluded(rays[i]));
      if (found[i]) expect_same(hits[i], h);
    }
  }
}

TEST(RayScene, ParallelQueriesMatchSerial) {
  const RayScene rs = build_ok(mixed_scene());
  const std::vector<Ray> rays = random_rays(20000, 5);
  std::vector<Hit> serial(rays.size()), parallel(rays.size());
  std::vector<std::uint8_t> found(rays.size()), pfound(rays.size()), pblocked(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) found[i] = rs.intersect(rays[i], serial[i]);
  std::vector<std::thread> threads;
  const int n = 4;
  for (int k = 0; k < n; ++k)
    threads.emplace_back([&, k] {
      for (std::size_t i = k; i < rays.size(); i += n) {
        pfound[i] = rs.intersect(rays[i], parallel[i]);
        pblocked[i] = rs.occluded(rays[i]);
      }
    });
  for (std::thread& t : threads) t.join();
  for (std::size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(found[i], pfound[i]);
    ASSERT_EQ(found[i], pblocked[i]);
    if (found[i]) expect_same(serial[i], parallel[i]);
  }
}

TEST(RayScene, BuildsInParallel) {
  const Scene s = mixed_scene();
  std::vector<std::thread> threads;
  std::vector<int> ok(4);
  for (int k = 0; k < 4; ++k)
    threads.emplace_back([&, k] {
      Expected<RayScene> r = RayScene::build(s);
      Hit h;
      ok[k] = r.ok() && r->intersect(Ray{{0, 3, 0}, {0, -1, 0}}, h) && h.kind == ShapeKind::disk;
    });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(ok, std::vector<int>(4, 1));
}

TEST(RayScene, EmptySceneMissesEverything) {
  const RayScene rs = build_ok(Scene{});
  for (const Ray& r : random_rays(100, 6)) {
    Hit h;
    EXPECT_FALSE(rs.intersect(r, h));
    EXPECT_FALSE(rs.occluded(r));
  }
  EXPECT_GT(rs.epsilon(), 0);
  EXPECT_GE(RayScene::estimate_bytes(Scene{}), rs.bytes());
}

TEST(RayScene, ErrorsSurfaceAsError) {
  Scene s;
  s.meshes.push_back(quad({0, 0, 0}, {1, 0, 0}, {0, 0, 1}));
  s.meshes[0].triangles[1][2] = 4;
  Expected<RayScene> r = RayScene::build(s);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("index 4 out of range"), std::string::npos) << r.error().message;

  s.meshes[0].triangles[1][2] = 3;
  s.meshes[0].materials.pop_back();
  r = RayScene::build(s);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("materials"), std::string::npos) << r.error().message;

  // Embree's own failure: an allocation refused past the limit comes back as an Error, and the
  // device works afterwards.
  s = mixed_scene();
  r = RayScene::build(s, 1000);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("memory"), std::string::npos) << r.error().message;
  EXPECT_TRUE(RayScene::build(s).ok());
}

// A closed box of quads (the Cornell box's shape) at a scale, with a light quad under its
// ceiling.
Scene box_scene(float size, Vec3 offset) {
  Scene s;
  const Vec3 o = offset;
  const float L = size;
  s.meshes.push_back(quad(o, {L, 0, 0}, {0, 0, L}));                  // floor
  s.meshes.push_back(quad(o + Vec3{0, L, 0}, {L, 0, 0}, {0, 0, L}));  // ceiling
  s.meshes.push_back(quad(o, {0, L, 0}, {0, 0, L}));                  // left
  s.meshes.push_back(quad(o + Vec3{L, 0, 0}, {0, L, 0}, {0, 0, L}));  // right
  s.meshes.push_back(quad(o, {L, 0, 0}, {0, L, 0}));                  // back
  s.meshes.push_back(quad(o + Vec3{0, 0, L}, {L, 0, 0}, {0, L, 0}));  // front
  s.meshes.push_back(quad(o + Vec3{0.35f, 0.99f, 0.35f} * L, {0.3f * L, 0, 0}, {0, 0, 0.3f * L}));
  s.spheres.push_back({o + Vec3{0.3f, 0.25f, 0.6f} * L, 0.2f * L});
  s.disks.push_back({o + Vec3{0.7f, 0.5f, 0.3f} * L, normalize(Vec3{1, 2, 0.5f}), 0.15f * L});
  return s;
}

// Directions leaving a surface with normal n, many of them grazing.
Vec3 leaving(std::mt19937& rng, Vec3 n, int i) {
  Vec3 d = random_unit(rng);
  d = d - dot(d, n) * n;  // in the plane
  const float lift = i % 4 == 0 ? 1e-4f : i % 4 == 1 ? 1e-2f : i % 4 == 2 ? 0.2f : 1.0f;
  return normalize(normalize(d) + lift * n);
}

TEST(RaySceneSpawn, RaysLeavingASurfaceNeverHitIt) {
  struct Config {
    float size;
    Vec3 offset;
  };
  for (Config c : {Config{555, {0, 0, 0}}, Config{555, {-277, -10, -277}}, Config{0.01f, {0, 0, 0}},
                   Config{0.01f, {0.3f, 0.2f, -0.1f}}, Config{1, {1000, 1000, 1000}}}) {
    const Scene s = box_scene(c.size, c.offset);
    const RayScene rs = build_ok(s);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.01f, 0.99f);
    int self = 0, tested = 0;
    for (int i = 0; i < 40000; ++i) {
      // A first hit from inside the box, then a ray leaving it to either side.
      const Vec3 o = c.offset + Vec3{u(rng), u(rng), u(rng)} * c.size;
      Hit h;
      if (!rs.intersect(Ray{o, random_unit(rng)}, h)) continue;
      const Vec3 n = i % 2 ? h.geometric_normal : -h.geometric_normal;
      const Vec3 d = leaving(rng, n, i);
      // Into a sphere the ray meets it again elsewhere; every other surface here is planar.
      if (h.kind == ShapeKind::sphere && dot(d, h.geometric_normal) < 0) continue;
      Hit h2;
      ++tested;
      if (rs.intersect(Ray{rs.spawn(h.position, h.geometric_normal, d), d}, h2) &&
          h2.kind == h.kind && h2.shape == h.shape)
        ++self;
    }
    EXPECT_GT(tested, 10000);
    EXPECT_EQ(self, 0) << "size " << c.size;
    EXPECT_LT(rs.epsilon(), 1e-3f * (c.size + std::abs(c.offset.x)));
  }
}

TEST(RaySceneSpawn, ShadowRaysReachTheLightButNotThroughBlockers) {
  for (float size : {0.01f, 1.0f, 555.0f}) {
    Scene s = box_scene(size, {0, 0, 0});
    const RayScene rs = build_ok(s);
    const std::size_t light = 6;
    const Vec3 corner = s.meshes[light].positions[0];
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> u(0.01f, 0.99f);
    int blocked = 0;
    for (int i = 0; i < 5000; ++i) {
      const Vec3 p{u(rng) * size, 0, u(rng) * size};  // on the floor
      const Vec3 target = corner + Vec3{u(rng) * 0.3f * size, 0, u(rng) * 0.3f * size};
      Ray r = rs.shadow_ray(p, {0, 1, 0}, target);
      Hit h;
      // What blocks it must be the sphere or the disk, never the floor or the light itself.
      if (rs.intersect(r, h)) {
        ++blocked;
        EXPECT_NE(h.kind, ShapeKind::triangle) << h.shape;
      }
      EXPECT_EQ(rs.occluded(r), rs.intersect(r, h));
      r = rs.shadow_ray(p, {0, 1, 0}, target, {0, -1, 0});
      if (rs.intersect(r, h)) {
        EXPECT_NE(h.kind, ShapeKind::triangle) << h.shape;
      }
    }
    EXPECT_LT(blocked, 4000);

    // Thin blockers 20 offsets above the floor and 20 below the light are found.
    const float gap = 20 * rs.epsilon();
    Scene s2 = s;
    s2.meshes.push_back(
        quad({0.4f * size, gap, 0.4f * size}, {0.05f * size, 0, 0}, {0, 0, 0.05f * size}));
    s2.meshes.push_back(quad(corner + Vec3{0.1f * size, -gap, 0.1f * size}, {0.05f * size, 0, 0},
                             {0, 0, 0.05f * size}));
    const RayScene rs2 = build_ok(s2);
    const Vec3 p{0.425f * size, 0, 0.425f * size};
    // Straight up through the first blocker; from the middle of the floor to the second one.
    EXPECT_TRUE(rs2.occluded(rs2.shadow_ray(p, {0, 1, 0}, p + Vec3{0, 0.99f * size, 0})));
    const Vec3 target = corner + Vec3{0.125f * size, 0, 0.125f * size};
    const Vec3 q{target.x + 0.01f * size, 0, target.z};
    EXPECT_TRUE(rs2.occluded(rs2.shadow_ray(q, {0, 1, 0}, target)));
    EXPECT_TRUE(rs2.occluded(rs2.shadow_ray(q, {0, 1, 0}, target, {0, -1, 0})));
    EXPECT_FALSE(rs.occluded(rs.shadow_ray(q, {0, 1, 0}, target)));
  }
}

// Light points seen edge-on (cosine down to 1e-3) do not shadow themselves, with or without the
// light's normal.
TEST(RaySceneSpawn, GrazingShadowRaysToALight) {
  for (float size : {0.01f, 1.0f, 555.0f}) {
    Scene s;
    s.meshes.push_back(
        quad(Vec3{0, 1, 0} * size, Vec3{0.3f, 0, 0} * size, Vec3{0, 0, 0.3f} * size));
    s.meshes.push_back(quad(Vec3{2, 0, 0} * size, Vec3{0, 0, 1} * size, Vec3{0, 2, 0} * size));
    const RayScene rs = build_ok(s);
    std::mt19937 rng(10);
    std::uniform_real_distribution<float> u(0.001f, 0.299f);
    for (float drop : {1e-3f, 1e-2f, 0.1f}) {
      int blocked = 0;
      for (int i = 0; i < 2000; ++i) {
        // A point on the wall at x = 2, a little below the light's plane.
        const Vec3 p = Vec3{2, 1 - drop, u(rng)} * size;
        const Vec3 target = Vec3{u(rng), 1, u(rng)} * size;
        blocked += rs.occluded(rs.shadow_ray(p, {-1, 0, 0}, target, {0, 1, 0}));
        blocked += rs.occluded(rs.shadow_ray(p, {-1, 0, 0}, target));
      }
      EXPECT_EQ(blocked, 0) << "size " << size << " drop " << drop;
    }
  }
}

TEST(RayScene, EstimateIsAtLeastTheMeasuredBytes) {
  for (int n : {1, 30, 300}) {
    Scene s;
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-1, 1);
    TriangleMesh m;
    for (int i = 0; i < n * n; ++i) {
      const Vec3 c{u(rng), u(rng), u(rng)};
      const auto b = std::uint32_t(m.positions.size());
      m.positions.insert(m.positions.end(),
                         {c, c + random_unit(rng) * 0.05f, c + random_unit(rng) * 0.05f});
      m.triangles.push_back({b, b + 1, b + 2});
      m.materials.push_back(0);
    }
    s.meshes.push_back(m);
    for (int i = 0; i < n * 10; ++i) {
      s.spheres.push_back({{u(rng), u(rng), u(rng)}, 0.01f});
      s.disks.push_back({{u(rng), u(rng), u(rng)}, random_unit(rng), 0.01f});
    }
    const RayScene rs = build_ok(s);
    EXPECT_GT(rs.bytes(), std::uint64_t(n) * n * 28);  // at least Embree's copies
    EXPECT_GE(RayScene::estimate_bytes(s), rs.bytes()) << n;
  }
}

TEST(RayScene, MovedSceneStillAnswers) {
  RayScene a = build_ok(mixed_scene());
  RayScene b = std::move(a);
  Hit h;
  EXPECT_TRUE(b.intersect(Ray{{0, 3, 0}, {0, -1, 0}}, h));
  EXPECT_EQ(h.kind, ShapeKind::disk);
}

}  // namespace
}  // namespace penumbra::spaceland
