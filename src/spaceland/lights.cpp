#include "spaceland/lights.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/math.hpp"
#include "spaceland/color.hpp"
#include "spaceland/sampling.hpp"
#include "spaceland/sky.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland {

namespace {

// 1 - cos(theta_max) of a sphere of radius r seen from distance d > r, without cancellation.
double cone_width(double r, double d) {
  const double s2 = (r * r) / (d * d);
  return s2 / (1 + std::sqrt(std::max(0.0, 1 - s2)));
}

// Whether p is outside the sphere by more than the rounding of a point on it, so that the cone it
// subtends can be sampled; dc is p's distance to the centre. A hit on the sphere is rounded to
// float and its distance to the centre lands above the radius as often as below (a quarter of
// the hits on a sphere off the origin): taken for outside, a point on the inside of an emitting
// sphere would sample the near intersection of its own cone, which is itself, and its shadow ray
// would never reach the far side. Within the margin, sampling by area stays exact: points on the
// far side are hidden by the near side, and pdf() takes the same branch as sample().
bool outside_sphere(const Sphere& s, Vec3 p, double& dc) {
  dc = length(s.center - p);
  const double c = std::max({std::abs(s.center.x), std::abs(s.center.y), std::abs(s.center.z)});
  return dc > s.radius + 0x1.0p-16 * (s.radius + c);
}

Vec3 triangle_normal(const TriangleMesh& m, std::uint32_t t, float& area) {
  const auto& tri = m.triangles[t];
  const Vec3 c =
      cross(m.positions[tri[1]] - m.positions[tri[0]], m.positions[tri[2]] - m.positions[tri[0]]);
  const float len = length(c);
  area = 0.5f * len;
  return len > 0 ? c / len : Vec3{0, 1, 0};
}

}  // namespace

Lights::Lights(const Scene& scene) : scene_(&scene), background_(scene) {
  auto emits = [&](std::uint32_t material) {
    return !is_black(scene.materials[material].emission);
  };
  triangle_emitter_.resize(scene.meshes.size());
  for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
    const TriangleMesh& mesh = scene.meshes[m];
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      if (!emits(mesh.materials[t])) continue;
      float area = 0;
      triangle_normal(mesh, std::uint32_t(t), area);
      if (!(area > 0)) continue;  // a degenerate triangle sends no light
      if (triangle_emitter_[m].empty()) triangle_emitter_[m].assign(mesh.triangles.size(), -1);
      triangle_emitter_[m][t] = int(emitters_.size());
      emitters_.push_back({ShapeKind::triangle, std::uint32_t(m), std::uint32_t(t), area,
                           scene.materials[mesh.materials[t]].emission});
    }
  }
  sphere_emitter_.assign(scene.spheres.size(), -1);
  for (std::size_t i = 0; i < scene.spheres.size(); ++i) {
    const Sphere& s = scene.spheres[i];
    if (!emits(s.material)) continue;
    sphere_emitter_[i] = int(emitters_.size());
    emitters_.push_back({ShapeKind::sphere, std::uint32_t(i), 0,
                         float(4 * kPi * s.radius * s.radius),
                         scene.materials[s.material].emission});
  }
  disk_emitter_.assign(scene.disks.size(), -1);
  for (std::size_t i = 0; i < scene.disks.size(); ++i) {
    const Disk& d = scene.disks[i];
    if (!emits(d.material)) continue;
    disk_emitter_[i] = int(emitters_.size());
    emitters_.push_back({ShapeKind::disk, std::uint32_t(i), 0, float(kPi * d.radius * d.radius),
                         scene.materials[d.material].emission});
  }
  // Picked by power (mean emitted radiance times area); both sides emit, which scales all alike.
  double total = 0;
  cdf_.reserve(emitters_.size());
  for (const Emitter& e : emitters_) {
    total += double(average(e.emission)) * e.area;
    cdf_.push_back(total);
  }
  for (double& c : cdf_) c /= total;
  if (!cdf_.empty()) cdf_.back() = 1;

  if (background_.has_sun()) {
    orthonormal_basis(background_.sun_direction(), sun_t_, sun_b_);
    sun_pdf_ = float(1 / (2 * kPi * background_.sun_one_minus_cos()));
  }
}

std::uint64_t Lights::bytes() const {
  std::uint64_t b = emitters_.size() * (sizeof(Emitter) + sizeof(double));
  for (const auto& v : triangle_emitter_) b += v.size() * sizeof(int);
  return b + (sphere_emitter_.size() + disk_emitter_.size()) * sizeof(int);
}

float Lights::pick_probability(int e) const {
  return float(cdf_[std::size_t(e)] - (e > 0 ? cdf_[std::size_t(e) - 1] : 0.0));
}

float Lights::solid_angle_pdf(const Emitter& e, Vec3 p, Vec3 q, Vec3 n) const {
  const Vec3 d = q - p;
  const float dist2 = dot(d, d);
  if (e.kind == ShapeKind::sphere) {
    const Sphere& s = scene_->spheres[e.shape];
    double dc;
    if (outside_sphere(s, p, dc)) return float(1 / (2 * kPi * cone_width(s.radius, dc)));
  }
  const float cos_l = std::abs(dot(n, d)) / std::sqrt(dist2);
  if (!(cos_l > 0)) return 0;
  return dist2 / (e.area * cos_l);
}

LightSample Lights::sample(Vec3 p, float u_pick, std::array<float, 2> u) const {
  LightSample ls;
  if (emitters_.empty()) return ls;
  const int e = int(std::min<std::ptrdiff_t>(
      std::lower_bound(cdf_.begin(), cdf_.end(), double(u_pick)) - cdf_.begin(),
      std::ptrdiff_t(cdf_.size()) - 1));
  const Emitter& em = emitters_[std::size_t(e)];
  const float pick = pick_probability(e);
  if (!(pick > 0)) return ls;
  ls.kind = em.kind;
  ls.shape = em.shape;
  ls.primitive = em.primitive;
  Vec3 q, n;
  std::optional<Rgb> textured;
  if (em.kind == ShapeKind::triangle) {
    const TriangleMesh& m = scene_->meshes[em.shape];
    const auto& tri = m.triangles[em.primitive];
    float a = u[0], b = u[1];
    if (a + b > 1) {
      a = 1 - a;
      b = 1 - b;
    }
    const Vec3 p0 = m.positions[tri[0]];
    q = p0 + (m.positions[tri[1]] - p0) * a + (m.positions[tri[2]] - p0) * b;
    float area;
    n = triangle_normal(m, em.primitive, area);
    const Material& material = scene_->materials[m.materials[em.primitive]];
    if (material.emission_texture.index >= 0) {
      // A textured emitter: the radiance at the sampled point (picked by its factor's power).
      Hit h;
      h.kind = ShapeKind::triangle;
      h.shape = em.shape;
      h.primitive = em.primitive;
      h.material = m.materials[em.primitive];
      h.b1 = a;
      h.b2 = b;
      if (!m.uvs.empty()) {
        const float c = 1 - a - b;
        h.u = c * m.uvs[tri[0]][0] + a * m.uvs[tri[1]][0] + b * m.uvs[tri[2]][0];
        h.v = c * m.uvs[tri[0]][1] + a * m.uvs[tri[1]][1] + b * m.uvs[tri[2]][1];
      }
      textured = emission_at(*scene_, h);
    }
  } else if (em.kind == ShapeKind::sphere) {
    const Sphere& s = scene_->spheres[em.shape];
    const Vec3 to_c = s.center - p;
    double dc;
    if (outside_sphere(s, p, dc)) {
      // Uniform in the cone the sphere subtends: exact solid-angle sampling.
      const double w = cone_width(s.radius, dc);
      const Vec3 axis = to_c / float(dc);
      Vec3 t, b;
      orthonormal_basis(axis, t, b);
      const Vec3 dir = cone_direction(axis, t, b, w, u);
      // The nearer intersection with the sphere (or the tangent point when it grazes).
      const double b_half = dot(dir, to_c);
      const double disc = std::max(0.0, b_half * b_half - (dc * dc - double(s.radius) * s.radius));
      const double dist = b_half - std::sqrt(disc);
      q = p + dir * float(dist);
      n = normalize(q - s.center);
      ls.direction = dir;
      ls.distance = float(dist);
      ls.point = q;
      ls.normal = n;
      ls.radiance = em.emission;
      ls.pdf = float(pick / (2 * kPi * w));
      return ls;
    }
    // Inside: uniform on the sphere (by area).
    n = uniform_sphere(u);
    q = s.center + n * s.radius;
  } else {
    const Disk& d = scene_->disks[em.shape];
    const double r = d.radius * std::sqrt(double(u[0])), phi = kTwoPi * u[1];
    Vec3 t, b;
    orthonormal_basis(d.normal, t, b);
    q = d.center + t * float(r * std::cos(phi)) + b * float(r * std::sin(phi));
    n = d.normal;
  }
  const Vec3 d = q - p;
  const float dist = length(d);
  if (!(dist > 0)) return ls;
  ls.direction = d / dist;
  ls.distance = dist;
  ls.point = q;
  ls.normal = n;
  ls.radiance = textured ? *textured : em.emission;
  ls.pdf = pick * solid_angle_pdf(em, p, q, n);
  return ls;
}

int Lights::index_of(const Hit& hit) const {
  switch (hit.kind) {
    case ShapeKind::triangle: {
      const auto& v = triangle_emitter_[hit.shape];
      return v.empty() ? -1 : v[hit.primitive];
    }
    case ShapeKind::sphere:
      return sphere_emitter_[hit.shape];
    case ShapeKind::disk:
      return disk_emitter_[hit.shape];
  }
  return -1;
}

float Lights::pdf(Vec3 p, const Hit& hit) const {
  const int e = index_of(hit);
  if (e < 0) return 0;
  return pick_probability(e) *
         solid_angle_pdf(emitters_[std::size_t(e)], p, hit.position, hit.geometric_normal);
}

LightSample Lights::sample_sun(std::array<float, 2> u) const {
  LightSample ls;
  if (!background_.has_sun()) return ls;
  ls.direction = cone_direction(background_.sun_direction(), sun_t_, sun_b_,
                                background_.sun_one_minus_cos(), u);
  ls.distance = std::numeric_limits<float>::infinity();  // shadow rays go to the sky
  ls.radiance = background_.sun();
  ls.pdf = sun_pdf_;
  ls.sun = true;
  return ls;
}

}  // namespace penumbra::spaceland
