// An independent review of the 3D path tracer against closed forms and brute-force integrals:
// emitting spheres seen from inside (with a sphere within, with absorbing fog), several emitters
// of every kind at once (disk, quad, sphere: the power pick and MIS across them), a tilted
// triangle light integrated numerically, and a wide sun over a sky gradient (MIS where both
// techniques matter).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/scene_builders.hpp"

namespace penumbra::spaceland {
namespace {

using namespace penumbra::spaceland::testing;

constexpr double kPi = std::numbers::pi;

ImageRgb render_image(const Scene& s, const RenderOptions& o) {
  Expected<RenderResult> r = render(s, o);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? r->radiance : ImageRgb{};
}

ImageRgb aov(const Scene& s, Aov which) {
  RenderOptions o = pt(1);
  o.aov = which;
  return render_image(s, o);
}

double channel(Rgb c, int k) {
  return k == 0 ? c.r : k == 1 ? c.g : c.b;
}

// Compares every pixel the predicate accepts with `want(i, j, channel)`: the mean ratio over
// those pixels within `mean_tol` of 1, the worst pixel within `pixel_tol`.
struct Check {
  double mean_ratio = 0, worst = 0;
  int pixels = 0;
};
Check compare(const ImageRgb& got, const std::function<bool(int, int)>& use,
              const std::function<double(int, int, int)>& want) {
  Check c;
  double sum_got = 0, sum_want = 0;
  for (int j = 0; j < got.height(); ++j)
    for (int i = 0; i < got.width(); ++i) {
      if (!use(i, j)) continue;
      for (int k = 0; k < 3; ++k) {
        const double w = want(i, j, k), g = channel(got.at(i, j), k);
        sum_got += g;
        sum_want += w;
        c.worst = std::max(c.worst, w > 0 ? std::abs(g / w - 1) : std::abs(g));
      }
      ++c.pixels;
    }
  c.mean_ratio = sum_want > 0 ? sum_got / sum_want : 1 + sum_got;
  return c;
}

// Where a pixel's noise is large (an emitter picked rarely), a fixed tolerance says little:
// renders with `seeds` independent seeds give each pixel a mean and a standard error, and every
// pixel's mean must lie within `z` standard errors of the truth (Student's t with 15 degrees of
// freedom exceeds 6 with probability 2.4e-5: about 0.05 false alarms over 2000 values; more
// seeds where an emitter is seen edge-on and the tail is heavy). Also
// returns the mean ratio over the pixels.
struct Stat {
  double mean_ratio = 0, worst_z = 0, worst_rel = 0;  // worst_rel: that pixel's error
  int pixels = 0;
};
Stat compare_seeds(const Scene& s, int spp, int seeds, const std::function<bool(int, int)>& use,
                   const std::function<double(int, int, int)>& want) {
  std::vector<ImageRgb> imgs;
  for (int k = 0; k < seeds; ++k) {
    RenderOptions o = pt(spp);
    o.pt.seed = std::uint64_t(k) + 1;
    imgs.push_back(render_image(s, o));
  }
  Stat st;
  double sum_got = 0, sum_want = 0;
  for (int j = 0; j < imgs[0].height(); ++j)
    for (int i = 0; i < imgs[0].width(); ++i) {
      if (!use(i, j)) continue;
      for (int c = 0; c < 3; ++c) {
        double m = 0, m2 = 0;
        for (const ImageRgb& img : imgs) {
          const double g = channel(img.at(i, j), c);
          m += g / seeds;
          m2 += g * g / seeds;
        }
        const double se = std::sqrt(std::max(0.0, m2 - m * m) / (seeds - 1));
        const double w = want(i, j, c);
        sum_got += m;
        sum_want += w;
        const double z = std::abs(m - w) / std::max(se, 1e-6 * w);
        if (z > st.worst_z) st.worst_rel = m / w - 1;
        st.worst_z = std::max(st.worst_z, z);
      }
      ++st.pixels;
    }
  st.mean_ratio = sum_got / sum_want;
  return st;
}

// A closed sphere of radius R (emission le_b, albedo a_b) around a concentric sphere of radius
// rho R (emission le_s, albedo a_s). By symmetry every point of either sphere has the same
// radiance; a point of the outer sphere sees the inner one over a projected solid angle
// pi f (f = rho^2, a cap on its normal) and the outer sphere over pi (1 - f); a point of the inner
// one sees only the outer sphere. With B and S the two radiances after n reflections:
//   B_n = le_b + a_b (f S_{n-1} + (1 - f) B_{n-1}),  S_n = le_s + a_s B_{n-1}.
struct Nested {
  double le_b[3], a_b[3], le_s[3], a_s[3], rho;  // rho: the inner radius over the outer one
  void radiances(int n, int c, double& b, double& s) const {
    const double f = rho * rho;
    b = le_b[c];
    s = le_s[c];
    for (int k = 0; k < n; ++k) {
      const double b1 = le_b[c] + a_b[c] * (f * s + (1 - f) * b);
      const double s1 = le_s[c] + a_s[c] * b;
      b = b1;
      s = s1;
    }
  }
};

Rgb rgb(const double v[3]) {
  return {float(v[0]), float(v[1]), float(v[2])};
}

Scene nested_scene(const Nested& n) {
  Scene s;
  // Off the origin and with a radius that is no power of two, so that the distance from the
  // centre to a hit rounds above the radius for a quarter of the hits (never at R = 1 about
  // the origin).
  const Vec3 c{2.1f, 1.7f, -0.9f};
  const float r = 1.3f;
  // Inside the outer sphere, looking at the inner one: both fill part of the image.
  s.camera = camera(c + Vec3{0.1f, 0.05f, 0.8f} * r, c - Vec3{0, 0, 1}, 24, 18, 110);
  add_sphere(s, c, r, add_material(s, rgb(n.a_b), rgb(n.le_b)));
  add_sphere(s, c, float(n.rho) * r, add_material(s, rgb(n.a_s), rgb(n.le_s)));
  return s;
}

void expect_nested(const Nested& n, int spp, double mean_tol, double pixel_tol) {
  const Scene s = nested_scene(n);
  const ImageRgb obj = aov(s, Aov::object);
  for (int bounces = 1; bounces <= 4; ++bounces) {
    const ImageRgb img = render_image(s, pt(spp, bounces));
    for (int which = 0; which < 2; ++which) {
      const Check c = compare(
          img, [&](int i, int j) { return int(obj.at(i, j).r) == which; },
          [&](int, int, int k) {
            double b, sr;
            n.radiances(bounces, k, b, sr);
            return which == 0 ? b : sr;
          });
      ASSERT_GT(c.pixels, 40) << which;
      EXPECT_NEAR(c.mean_ratio, 1.0, mean_tol) << "bounces " << bounces << " sphere " << which;
      EXPECT_LT(c.worst, pixel_tol) << "bounces " << bounces << " sphere " << which;
      std::printf("nested bounces %d sphere %d: mean ratio - 1 = %+.5f, worst pixel %.5f\n",
                  bounces, which, c.mean_ratio - 1, c.worst);
    }
  }
}

// A point on the inside of an emitting sphere must not take the sphere for "seen from outside"
// (its distance to the centre rounds above the radius half the time): its shadow rays must reach
// the far side, where the inner sphere hides part of it.
TEST(SpacelandPtReview, EmittingSphereAroundADarkSphereGivesItsClosedForm) {
  Nested n{{1, 0.5, 0.2}, {0.6, 0.5, 0.4}, {0, 0, 0}, {0, 0, 0}, 0.5};
  expect_nested(n, 128, 0.004, 0.03);
}

// Both spheres emit and reflect: a furnace that is not all-emitting at every order, the emitter
// with albedo > 0, BSDF-sampled hits of both spheres from inside and outside weighted by MIS.
TEST(SpacelandPtReview, NestedEmittingReflectingSpheresGiveTheirRecursion) {
  Nested n{{0.2, 0.1, 0.05}, {0.7, 0.6, 0.5}, {3, 5, 8}, {0.4, 0.5, 0.6}, 0.4};
  expect_nested(n, 128, 0.004, 0.03);
}

// Absorbing grey fog inside an emitting sphere (scene_builders.hpp: absorbing_fog_sphere): the
// camera ray passes with probability T(R), the wall point's irradiance comes through the fog.
TEST(SpacelandPtReview, AbsorbingFogInsideAnEmittingSphereGivesItsClosedForm) {
  const FogSphere f = absorbing_fog_sphere();
  const Scene& s = f.scene;
  const double want = f.want;
  const int spp = 256;
  const ImageRgb img = render_image(s, pt(spp));
  const Check c = compare(
      img, [](int, int) { return true; }, [&](int, int, int) { return want; });
  // The camera ray passes (weight 1) with probability p = T or is absorbed: over 16 x 12 x spp
  // samples the mean's relative standard error is sqrt((1 - p) / (p N)) = 0.0044; the NEE part
  // adds a little. Four of those.
  const double p = f.transmittance, se = std::sqrt((1 - p) / (p * 16 * 12 * spp));
  std::printf("fog sphere: mean ratio - 1 = %+.5f (standard error %.5f)\n", c.mean_ratio - 1, se);
  EXPECT_NEAR(c.mean_ratio, 1.0, 4 * se);
}

// Irradiance on a horizontal plane at the origin's height (point (x, 0, z), normal up) from
// Lambertian emitters of radiance 1, closed forms:
// - a horizontal disk (centre c, radius r) above it: pi F with
//   F = (1 - (h^2 + q^2 - r^2) / sqrt((h^2 + q^2 + r^2)^2 - 4 r^2 q^2)) / 2, q the offset;
// - a horizontal rectangle [x0, x1] x [z0, z1] at height h: pi times the signed sum over its
//   four corners of the corner form factor
//   (A / sqrt(1 + A^2) atan(B / sqrt(1 + A^2)) + B / sqrt(1 + B^2) atan(A / sqrt(1 + B^2))) / 2pi;
// - a sphere wholly above the plane: pi r^2 cos(theta) / d^2.
double disk_irradiance(double x, double z, Vec3 c, double r) {
  const double h = c.y, q2 = (x - c.x) * (x - c.x) + (z - c.z) * (z - c.z);
  const double s = h * h + q2 + r * r;
  return kPi * 0.5 * (1 - (h * h + q2 - r * r) / std::sqrt(s * s - 4 * r * r * q2));
}

double corner(double a, double b, double h) {
  const double A = std::abs(a) / h, B = std::abs(b) / h;
  const double sa = std::sqrt(1 + A * A), sb = std::sqrt(1 + B * B);
  const double f = (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2 * kPi);
  return (a < 0 ? -f : f) * (b < 0 ? -1 : 1);
}

double rectangle_irradiance(double x, double z, double x0, double x1, double z0, double z1,
                            double h) {
  const double X0 = x0 - x, X1 = x1 - x, Z0 = z0 - z, Z1 = z1 - z;
  return kPi * (corner(X1, Z1, h) - corner(X0, Z1, h) - corner(X1, Z0, h) + corner(X0, Z0, h));
}

double sphere_irradiance(double x, double z, Vec3 c, double r) {
  const double dx = c.x - x, dy = c.y, dz = c.z - z, d2 = dx * dx + dy * dy + dz * dz;
  return kPi * r * r / d2 * (dy / std::sqrt(d2));
}

// A floor (a large disk of albedo 0.5 at y = 0) under a disk, a quad (two triangles of a mesh)
// and a sphere, all emitting with different colours and powers; the disk and the quad lie in one
// plane and cannot hide each other from the floor, the sphere lies wholly above that plane.
struct Lamps {
  Scene s;
  Vec3 disk_c{-1.2f, 2, 0.3f};
  float disk_r = 0.4f;
  float x0 = 0.6f, x1 = 1.4f, z0 = -0.9f, z1 = -0.3f, h = 2;
  Vec3 sphere_c{0.2f, 2.4f, 1.6f};
  float sphere_r = 0.25f;
  Rgb le_disk{3, 1, 0.5f}, le_quad{0.5f, 2, 1}, le_sphere{20, 25, 40};
};

Lamps lamps() {
  Lamps l;
  Scene& s = l.s;
  s.camera = camera({0, 6, 3}, {0, 0, 0}, 48, 36, 50);
  add_floor(s, 100, {0.5f, 0.5f, 0.5f});
  Disk d;
  d.center = l.disk_c;
  d.normal = {0, -1, 0};
  d.radius = l.disk_r;
  d.material = add_material(s, {0.3f, 0.3f, 0.3f}, l.le_disk);
  d.object = add_object(s, "disk");
  s.disks.push_back(d);
  TriangleMesh q;
  q.positions = {{l.x0, l.h, l.z0}, {l.x1, l.h, l.z0}, {l.x1, l.h, l.z1}, {l.x0, l.h, l.z1}};
  q.triangles = {{0, 1, 2}, {0, 2, 3}};
  q.materials.assign(2, add_material(s, {0.3f, 0.3f, 0.3f}, l.le_quad));
  q.object = add_object(s, "quad");
  s.meshes.push_back(q);
  add_sphere(s, l.sphere_c, l.sphere_r, add_material(s, {0.3f, 0.3f, 0.3f}, l.le_sphere));
  return l;
}

TEST(SpacelandPtReview, DiskQuadAndSphereLightsOnAFloorGiveTheirClosedForms) {
  const Lamps l = lamps();
  const ImageRgb pos = aov(l.s, Aov::position), obj = aov(l.s, Aov::object);
  // Floor points within 2.5 of the origin: lines from them to the sphere (bottom at 2.15) cross
  // the lamps' plane y = 2 within 0.25 + 4.1 x 0.65 / 2.65 = 1.26 of its axis, short of the disk
  // (1.51) and the quad (1.94): no lamp hides another.
  auto near = [&](int i, int j) {
    const Rgb p = pos.at(i, j);
    return obj.at(i, j).r == 0 && p.r * p.r + p.b * p.b < 2.5 * 2.5;
  };
  const Stat c = compare_seeds(l.s, 64, 16, near, [&](int i, int j, int k) {
    const Rgb p = pos.at(i, j);
    const double e_disk = disk_irradiance(p.r, p.b, l.disk_c, l.disk_r);
    const double e_quad = rectangle_irradiance(p.r, p.b, l.x0, l.x1, l.z0, l.z1, l.h);
    const double e_sphere = sphere_irradiance(p.r, p.b, l.sphere_c, l.sphere_r);
    return 0.5 / kPi *
           (channel(l.le_disk, k) * e_disk + channel(l.le_quad, k) * e_quad +
            channel(l.le_sphere, k) * e_sphere);
  });
  std::printf("lamps: %d pixels, mean ratio - 1 = %+.5f, worst |z| %.2f (%+.5f)\n", c.pixels,
              c.mean_ratio - 1, c.worst_z, c.worst_rel);
  EXPECT_GT(c.pixels, 400);
  EXPECT_NEAR(c.mean_ratio, 1.0, 0.002);
  EXPECT_LT(c.worst_z, 6);
}

// The disk light alone, on its axis: pi Le r^2 / (r^2 + h^2) exactly (one pixel, many samples).
TEST(SpacelandPtReview, DiskLightOnItsAxisGivesPiLeRSquaredOverRSquaredPlusHSquared) {
  Lamps l = lamps();
  l.s.meshes.clear();
  l.s.spheres.clear();
  l.s.camera = camera({l.disk_c.x, 1, l.disk_c.z}, {l.disk_c.x, 0, l.disk_c.z}, 1, 1, 1);
  l.s.camera.up = {0, 0, 1};
  const ImageRgb img = render_image(l.s, pt(1024));
  const double r = l.disk_r, h = l.disk_c.y;
  const double e = kPi * r * r / (r * r + h * h);
  const Rgb got = img.at(0, 0);
  std::printf("disk on axis: ratio - 1 = %+.6f\n", got.r / (0.5 / kPi * l.le_disk.r * e) - 1);
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(channel(got, k) / (0.5 / kPi * channel(l.le_disk, k) * e), 1.0, 2e-3) << k;
}

// A tilted triangle light over the floor: the irradiance integrated numerically over the
// triangle (midpoint rule on 160^2 sub-triangles; the integrand is smooth, error ~1e-5).
TEST(SpacelandPtReview, TiltedTriangleLightMatchesANumericalIntegral) {
  Scene s;
  s.camera = camera({0, 3, 4}, {0, 0, 0}, 24, 18, 50);
  add_floor(s, 100, {0.5f, 0.5f, 0.5f});
  const Vec3 v0{-0.6f, 1.2f, -0.4f}, v1{0.9f, 1.8f, -0.2f}, v2{0.1f, 1.0f, 0.7f};
  TriangleMesh t;
  t.positions = {v0, v1, v2};
  t.triangles = {{0, 1, 2}};
  const Rgb le{2, 3, 4};
  t.materials = {add_material(s, {0.5f, 0.5f, 0.5f}, le)};
  t.object = add_object(s, "triangle");
  s.meshes.push_back(t);
  const ImageRgb pos = aov(s, Aov::position), obj = aov(s, Aov::object);
  const int n = 400;
  const double e1[3] = {v1.x - v0.x, v1.y - v0.y, v1.z - v0.z};
  const double e2[3] = {v2.x - v0.x, v2.y - v0.y, v2.z - v0.z};
  const double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
  const double area2 = std::sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
  const double nl[3] = {cr[0] / area2, cr[1] / area2, cr[2] / area2};
  const double da = 0.5 * area2 / (n * n);
  auto irradiance = [&](double x, double z) {
    double e = 0;
    auto add = [&](double a, double b) {
      const double q[3] = {v0.x + a * e1[0] + b * e2[0], v0.y + a * e1[1] + b * e2[1],
                           v0.z + a * e1[2] + b * e2[2]};
      const double d[3] = {q[0] - x, q[1], q[2] - z};
      const double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], len = std::sqrt(d2);
      const double cos_p = d[1] / len;
      const double cos_l = std::abs(d[0] * nl[0] + d[1] * nl[1] + d[2] * nl[2]) / len;
      e += cos_p * cos_l / d2 * da;
    };
    // Sub-triangles of the n x n grid in barycentric (a, b): upright and inverted, at their
    // centroids.
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        add((i + 1.0 / 3) / n, (j + 1.0 / 3) / n);
        if (i + j + 1 < n) add((i + 2.0 / 3) / n, (j + 2.0 / 3) / n);
      }
    return e;
  };
  std::vector<double> e(pos.size() / 3, 0.0);  // one integral per pixel, not per channel
  for (int j = 0; j < pos.height(); ++j)
    for (int i = 0; i < pos.width(); ++i)
      if (obj.at(i, j).r == 0)
        e[std::size_t(j) * pos.width() + i] = irradiance(pos.at(i, j).r, pos.at(i, j).b);
  const Stat c = compare_seeds(
      s, 16, 64, [&](int i, int j) { return obj.at(i, j).r == 0; },
      [&](int i, int j, int k) {
        return 0.5 / kPi * channel(le, k) * e[std::size_t(j) * pos.width() + i];
      });
  std::printf("triangle: %d pixels, mean ratio - 1 = %+.5f, worst |z| %.2f (%+.5f)\n", c.pixels,
              c.mean_ratio - 1, c.worst_z, c.worst_rel);
  EXPECT_GT(c.pixels, 300);
  EXPECT_NEAR(c.mean_ratio, 1.0, 0.002);
  EXPECT_LT(c.worst_z, 6);
}

// A wide sun (45 degrees, 30 degrees from the zenith) over a sky gradient on a plane: the sun's
// cap is wholly above the horizon, E_sun = irradiance cos(30 deg); the sky gives
// pi horizon + 2 pi (zenith - horizon) / 3. BSDF sampling hits the sun often: the MIS weights
// of both techniques must sum to one.
TEST(SpacelandPtReview, WideSunOverASkyGradientGivesItsClosedForm) {
  Scene s;
  s.camera = camera({0, 2, 3}, {0, 0, 0}, 24, 18, 40);
  s.sky.zenith = {0.2f, 0.4f, 1.0f};
  s.sky.horizon = {0.8f, 0.7f, 0.6f};
  s.sky.ground = {5, 5, 5};  // below the plane's horizon: never reaches it
  s.has_sun = true;
  const double tilt = 30 * kPi / 180;
  s.sun.direction = {float(std::sin(tilt)), float(std::cos(tilt)), 0};
  s.sun.angular_radius = 45;
  s.sun.irradiance = {2, 1, 0.5f};
  add_floor(s, 100, {0.5f, 0.5f, 0.5f});
  const ImageRgb obj = aov(s, Aov::object);
  const ImageRgb img = render_image(s, pt(256));
  const Check c = compare(
      img, [&](int i, int j) { return obj.at(i, j).r == 0; },
      [&](int, int, int k) {
        const double h = channel(s.sky.horizon, k), z = channel(s.sky.zenith, k);
        const double e_sky = kPi * h + 2 * kPi * (z - h) / 3;
        const double e_sun = channel(s.sun.irradiance, k) * std::cos(tilt);
        return 0.5 / kPi * (e_sky + e_sun);
      });
  std::printf("wide sun: %d pixels, mean ratio - 1 = %+.5f, worst pixel %.5f\n", c.pixels,
              c.mean_ratio - 1, c.worst);
  EXPECT_GT(c.pixels, 300);
  EXPECT_NEAR(c.mean_ratio, 1.0, 0.002);
  EXPECT_LT(c.worst, 0.02);
}

}  // namespace
}  // namespace penumbra::spaceland
