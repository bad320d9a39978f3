// Building 3D scenes in code for the tests: materials, object lines, boxes, cameras, and render()
// where the test expects it to succeed.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "core/math.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"

namespace penumbra::spaceland::testing {

inline std::uint32_t add_material(Scene& s, Rgb albedo, Rgb emission = {}) {
  Material m;
  m.albedo = albedo;
  m.emission = emission;
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "m" + std::to_string(...).
  m.name = "m";
  m.name += std::to_string(s.materials.size());
  s.materials.push_back(m);
  return std::uint32_t(s.materials.size() - 1);
}

// A line of Scene::objects; returns the object's index.
inline int add_object(Scene& s, const std::string& what) {
  std::string line = "objects[";
  line += std::to_string(s.objects.size());
  line += "] (";
  line += what;
  line += ")";
  s.objects.push_back(line);
  return int(s.objects.size() - 1);
}

// The six faces of the box [lo, hi] as 12 flat triangles.
inline void add_box(Scene& s, Vec3 lo, Vec3 hi, std::uint32_t material) {
  TriangleMesh m;
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x)
        m.positions.push_back({x ? hi.x : lo.x, y ? hi.y : lo.y, z ? hi.z : lo.z});
  const std::uint32_t faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                                     {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& f : faces) {
    m.triangles.push_back({f[0], f[1], f[2]});
    m.triangles.push_back({f[0], f[2], f[3]});
  }
  m.materials.assign(m.triangles.size(), material);
  m.object = add_object(s, "box");
  s.meshes.push_back(m);
}

// The quad corner, corner + u, corner + u + v, corner + v as 2 flat triangles.
inline void add_quad(Scene& s, Vec3 corner, Vec3 u, Vec3 v, std::uint32_t material) {
  TriangleMesh m;
  m.positions = {corner, corner + u, corner + u + v, corner + v};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  m.materials.assign(2, material);
  m.object = add_object(s, "quad");
  s.meshes.push_back(m);
}

// The irradiance at p (unit normal n) from a polygon of radiance 1 above p's plane, unoccluded:
// Lambert's formula, half the sum over its edges of the angle each subtends at p times the
// cosine between n and the normal of the plane through p and the edge.
inline double polygon_irradiance(Vec3 p, Vec3 n, const std::vector<Vec3>& corners) {
  double sum = 0;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const Vec3 a = normalize(corners[i] - p), b = normalize(corners[(i + 1) % corners.size()] - p);
    const double angle = std::acos(std::clamp(double(dot(a, b)), -1.0, 1.0));
    sum += angle * double(dot(n, normalize(cross(a, b))));
  }
  return 0.5 * std::abs(sum);
}

// A disk of `radius` at y = 0 facing up (a floor, or an open plane when large); returns its object.
inline int add_floor(Scene& s, float radius, Rgb albedo) {
  Disk d;
  d.radius = radius;
  d.material = add_material(s, albedo);
  d.object = add_object(s, "disk");
  s.disks.push_back(d);
  return d.object;
}

inline Sphere add_sphere(Scene& s, Vec3 center, float radius, std::uint32_t material) {
  Sphere b;
  b.center = center;
  b.radius = radius;
  b.material = material;
  b.object = add_object(s, "sphere");
  s.spheres.push_back(b);
  return b;
}

inline Camera camera(Vec3 position, Vec3 look_at, int w, int h, float fov = 60,
                     Vec3 up = {0, 1, 0}) {
  Camera c;
  c.position = position;
  c.look_at = look_at;
  c.up = up;
  c.fov_y = fov;
  c.width = w;
  c.height = h;
  return c;
}

// An open plane (a disk 1000 across, albedo 0.6) under a uniform sky L = (1.5, 1, 0.5), seen at
// a slant: every plane pixel is a L, every sky pixel L.
inline Scene sky_plane() {
  Scene s;
  s.camera = camera({0.3f, 2, 3}, {0, 0, -1}, 64, 48, 60);
  s.sky = {{1.5f, 1, 0.5f}, {1.5f, 1, 0.5f}, {1.5f, 1, 0.5f}};
  add_floor(s, 1000, {0.6f, 0.6f, 0.6f});
  return s;
}

// Largest relative deviation of sky_plane()'s image from its closed form: plane pixels a L, sky
// pixels (the top rows) L.
inline double sky_plane_error(const ImageRgb& img) {
  double worst = 0;
  for (int j = 0; j < img.height(); ++j)
    for (int i = 0; i < img.width(); ++i) {
      const Rgb c = img.at(i, j);
      const double k = c.g < 0.8 ? 0.6 : 1.0;
      worst = std::max({worst, std::abs(c.r / (1.5 * k) - 1), std::abs(c.g / (1.0 * k) - 1),
                        std::abs(c.b / (0.5 * k) - 1)});
    }
  return worst;
}

// The path tracer with `spp` samples per pixel and `bounces`.
inline RenderOptions pt(int spp, int bounces = 1) {
  RenderOptions o;
  o.pt.spp = spp;
  o.bounces = bounces;
  return o;
}

inline RenderResult render_ok(const Scene& s, const RenderOptions& o) {
  Expected<RenderResult> r = render(s, o);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? *r : RenderResult{};
}

// Renders on 1 and on 2 threads and expects the same bits; returns the image.
inline ImageRgb same_bits_on_one_and_two_threads(const Scene& s, RenderOptions o) {
  o.threads = 1;
  const ImageRgb one = render_ok(s, o).radiance;
  o.threads = 2;
  const ImageRgb two = render_ok(s, o).radiance;
  EXPECT_EQ(one.size(), two.size());
  EXPECT_TRUE(one.size() == two.size() &&
              std::equal(one.data(), one.data() + one.size(), two.data()));
  return one;
}

// Two closed rooms side by side, [-1, 1]^3 and [1 + gap, 3] x [-1, 1]^2 (gap 0: one shared wall),
// walls of albedo 0.7; a sphere light (radius 0.3, Le 50) in the second; the camera in the first.
inline Scene two_closed_rooms(float gap) {
  Scene s;
  s.camera = camera({0, 0, 0.5f}, {0.2f, -0.3f, -1}, 48, 36, 80);
  const std::uint32_t wall = add_material(s, {0.7f, 0.7f, 0.7f});
  add_box(s, {-1, -1, -1}, {1, 1, 1}, wall);
  add_box(s, {1 + gap, -1, -1}, {3, 1, 1}, wall);
  add_sphere(s, {2, 0, 0}, 0.3f, add_material(s, {0, 0, 0}, {50, 50, 50}));
  return s;
}

// An enclosure whose walls all emit Le = (1, 0.5, 0.25) and reflect a = 0.6: every pixel is
// Le (1 + a + ... + a^N) at N bounces. With `fog`, a fog box inside that reflects as the walls
// do and emits sigma Le per unit length keeps the same answer: along any ray,
// (1 - T)(Le + a L') + T (Le + a L') = Le + a L'. The camera inside, w x h pixels.
inline Scene furnace(bool fog, int w, int h) {
  Scene s;
  s.camera = camera({0.1f, -0.2f, 0.3f}, {0.5f, 0.4f, -1}, w, h, 90);
  const Rgb le{1.0f, 0.5f, 0.25f};
  const float a = 0.6f;
  add_box(s, {-1, -1, -1}, {1, 1.5f, 2}, add_material(s, {a, a, a}, le));
  if (fog) {
    Medium m;
    m.center = {0, 0.2f, 0.4f};
    m.half_size = {0.8f, 1.0f, 1.2f};
    m.extinction = {0.5f, 1.0f, 2.0f};
    m.albedo = {a, a, a};
    m.emission = {m.extinction.r * le.r, m.extinction.g * le.g, m.extinction.b * le.b};
    s.media.push_back(m);
  }
  return s;
}

// Absorbing grey fog (sigma 0.5) inside a sphere of radius R = 1.3 emitting Le = 1 with albedo
// a = 0.8, seen from its centre (16 x 12 pixels) at one bounce: every pixel is the wall's
// radiance through the fog, exp(-sigma R) (Le + a / pi E), where the wall point's irradiance
// through the fog is E = 2 pi Le int_0^1 exp(-2 sigma R mu) mu dmu (the chord along
// cos theta = mu is 2 R mu long).
struct FogSphere {
  Scene scene;
  double want = 0;
  double transmittance = 0;  // exp(-sigma R), the camera ray's
};
inline FogSphere absorbing_fog_sphere() {
  FogSphere f;
  Scene& s = f.scene;
  const Vec3 o{2.1f, 1.7f, -0.9f};
  const float r = 1.3f;
  s.camera = camera(o, o + Vec3{0.3f, 0.2f, -1}, 16, 12, 60);
  const double le = 1, a = 0.8, sigma = 0.5, pi = kPi;
  add_sphere(s, o, r, add_material(s, {float(a), float(a), float(a)}, {float(le), 1, 1}));
  Medium m;
  m.center = o;
  m.half_size = {2, 2, 2};
  m.extinction = {float(sigma), float(sigma), float(sigma)};
  s.media.push_back(m);
  const double k = 2 * sigma * r;
  const double e = 2 * pi * le * (1 - std::exp(-k) * (1 + k)) / (k * k);
  f.transmittance = std::exp(-sigma * r);
  f.want = f.transmittance * (le + a / pi * e);
  return f;
}

// Each pixel's first hit: its world position and its object (-1 for the sky), through render's
// AOVs (the renderer's own G-buffer, so a closed form is evaluated where the pixel looks).
struct FirstHits {
  ImageRgb position, object;
};
inline FirstHits first_hits(const Scene& s) {
  RenderOptions o = pt(1);
  o.aov = Aov::position;
  FirstHits f;
  f.position = render_ok(s, o).radiance;
  o.aov = Aov::object;
  f.object = render_ok(s, o).radiance;
  return f;
}

// The relative RMSE of img's green over the pixels of object 0 (a floor) against want(p) at each
// pixel's floor point p; `pixels` receives how many were counted.
template <class Want>
double floor_error(const Scene& s, const ImageRgb& img, Want&& want, int& pixels) {
  const FirstHits hits = first_hits(s);
  double sum2 = 0, sum_want = 0;
  pixels = 0;
  for (int j = 0; j < img.height(); ++j)
    for (int i = 0; i < img.width(); ++i) {
      if (hits.object.at(i, j).r != 0) continue;
      const Rgb q = hits.position.at(i, j);
      const double w = want(Vec3{q.r, q.g, q.b});
      sum2 += (img.at(i, j).g - w) * (img.at(i, j).g - w);
      sum_want += w;
      ++pixels;
    }
  return pixels > 0 ? std::sqrt(sum2 / pixels) / (sum_want / pixels) : 0;
}

// The same against a sphere light's closed form a Le (r/d)^2 cos(theta) over a floor of albedo
// `a` (`le`: the light's green emission).
inline double sphere_light_floor_error(const Scene& s, const Sphere& light, double a, double le,
                                       const ImageRgb& img, int& pixels) {
  return floor_error(
      s, img,
      [&](Vec3 p) {
        const double dx = double(light.center.x) - p.x, dy = double(light.center.y) - p.y,
                     dz = double(light.center.z) - p.z;
        const double d2 = dx * dx + dy * dy + dz * dz, r2 = double(light.radius) * light.radius;
        return a * le * r2 / d2 * (dy / std::sqrt(d2));
      },
      pixels);
}

// A floor 100 wide (a disk of radius 50, albedo 0.5).
inline Scene wide_floor() {
  Scene s;
  add_floor(s, 50, {0.5f, 0.5f, 0.5f});
  return s;
}

// A sphere light of radius 0.3 over wide_floor(), in view or behind the camera, 96 x 72: the
// floor's relative RMSE against a Le (r/d)^2 cos(theta).
inline double wide_floor_error(const RenderOptions& o, bool behind) {
  Scene s = wide_floor();
  s.camera = camera({0, 2, 4}, {0, 0, 0}, 96, 72, 60);
  const float le = 30;
  const Vec3 at = behind ? Vec3{0.5f, 1.5f, 5.5f} : Vec3{0.3f, 1, -0.5f};
  const Sphere light = add_sphere(s, at, 0.3f, add_material(s, {0, 0, 0}, {le, le, le}));
  int n = 0;
  const double e = sphere_light_floor_error(s, light, 0.5, le, render_ok(s, o).radiance, n);
  EXPECT_GT(n, 96 * 72 / 3);
  return e;
}

// A shaped light emitting 30 over wide_floor(), in view or behind the camera, 96 x 72: a quad of
// side 0.5 facing down (emitting both ways), or a box of side 0.4; the floor's relative RMSE
// against a Le E / pi, E the sum of polygon_irradiance over the faces it sees (the quad's one,
// the box's faces turned towards the point).
inline double wide_floor_shape_error(const RenderOptions& o, bool behind, bool box) {
  Scene s = wide_floor();
  s.camera = camera({0, 2, 4}, {0, 0, 0}, 96, 72, 60);
  const float le = 30;
  const std::uint32_t lamp = add_material(s, {0, 0, 0}, {le, le, le});
  const Vec3 at = behind ? Vec3{0.25f, 1.5f, 5.25f} : Vec3{0.05f, 1, -0.75f};
  std::vector<std::vector<Vec3>> faces;
  std::vector<Vec3> outwards;
  if (box) {
    const float h = 0.2f;
    const Vec3 c = at + Vec3{0.25f, 0, 0.25f}, lo = c - Vec3{h, h, h}, hi = c + Vec3{h, h, h};
    add_box(s, lo, hi, lamp);
    for (int k = 0; k < 3; ++k)
      for (int side = 0; side < 2; ++side) {
        Vec3 n{};
        n[k] = side ? 1.0f : -1.0f;
        const int a = (k + 1) % 3, b = (k + 2) % 3;
        std::vector<Vec3> f(4, c + n * h);
        const float sa[4] = {-1, 1, 1, -1}, sb[4] = {-1, -1, 1, 1};
        for (int m = 0; m < 4; ++m)
          f[std::size_t(m)][a] += sa[m] * h, f[std::size_t(m)][b] += sb[m] * h;
        faces.push_back(f);
        outwards.push_back(n);
      }
  } else {
    const Vec3 u{0.5f, 0, 0}, v{0, 0, 0.5f};
    add_quad(s, at, u, v, lamp);
    faces.push_back({at, at + u, at + u + v, at + v});
    outwards.push_back({0, 0, 0});  // both sides
  }
  int n = 0;
  const double e = floor_error(
      s, render_ok(s, o).radiance,
      [&](Vec3 p) {
        double sum = 0;
        for (std::size_t f = 0; f < faces.size(); ++f)
          if (dot(outwards[f], outwards[f]) == 0 || dot(outwards[f], p - faces[f][0]) > 0)
            sum += polygon_irradiance(p, {0, 1, 0}, faces[f]);
        return 0.5 * le * sum / std::numbers::pi;
      },
      n);
  EXPECT_GT(n, 96 * 72 / 3);
  return e;
}

// A floor (a disk 1000 across at y = 0) of base colour `c`, metallic and roughness, seen from
// above at a slant; returns its object.
inline int add_glossy_floor(Scene& s, Rgb c, float metallic, float roughness) {
  const int object = add_floor(s, 1000, c);
  Material& m = s.materials[s.disks.back().material];
  m.metallic = metallic;
  m.roughness = roughness;
  return object;
}

// Relative RMS error and mean ratio of the floor's pixels against want(p, wo): each pixel's error
// relative to its own want (`Relative::pixel`), or the RMS error over the floor's mean want
// (`Relative::mean`, as `penumbra compare` does: dim pixels weigh by their light).
enum class Relative { pixel, mean };
template <class Want>
std::pair<double, double> glossy_floor_error(const Scene& s, const ImageRgb& img, int floor,
                                             Want&& want, Relative relative = Relative::pixel) {
  const FirstHits hits = first_hits(s);
  double sum = 0, got_sum = 0, want_sum = 0;
  int n = 0;
  for (int j = 0; j < img.height(); ++j)
    for (int i = 0; i < img.width(); ++i) {
      if (int(hits.object.at(i, j).r) != floor) continue;
      const Rgb q = hits.position.at(i, j);
      const Vec3 p{q.r, q.g, q.b};
      const double w = want(p, normalize(s.camera.position - p));
      const double got = img.at(i, j).g;
      const double e = relative == Relative::pixel ? got / w - 1 : got - w;
      sum += e * e;
      got_sum += got;
      want_sum += w;
      ++n;
    }
  EXPECT_GT(n, 300);
  const double rms = std::sqrt(sum / std::max(n, 1));
  return {relative == Relative::pixel ? rms : rms / (want_sum / std::max(n, 1)),
          got_sum / want_sum};
}

}  // namespace penumbra::spaceland::testing
