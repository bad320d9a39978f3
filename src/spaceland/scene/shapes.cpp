// Triangles of the analytic objects.
#include "spaceland/scene/shapes.hpp"

#include <cmath>
#include <cstdint>
#include <numbers>

namespace penumbra::spaceland {

namespace {

// Appends the parallelogram p, p + u, p + u + v, p + v with its flat normal (local space).
void add_parallelogram(TriangleMesh& mesh, Vec3 p, Vec3 u, Vec3 v) {
  const auto base = std::uint32_t(mesh.positions.size());
  const Vec3 n = normalize(cross(u, v));
  for (Vec3 q : {p, p + u, p + u + v, p + v}) {
    mesh.positions.push_back(q);
    mesh.normals.push_back(n);
  }
  mesh.triangles.push_back({base, base + 1, base + 2});
  mesh.triangles.push_back({base, base + 2, base + 3});
}

}  // namespace

void transform_mesh(TriangleMesh& mesh, const Affine& to_world) {
  for (Vec3& p : mesh.positions) p = to_world.point(p);
  for (Vec3& n : mesh.normals) n = to_world.normal(n);
}

TriangleMesh box_mesh(const Affine& to_world) {
  TriangleMesh mesh;
  // Each face as corner + u + v with cross(u, v) pointing out of the cube.
  for (int axis = 0; axis < 3; ++axis) {
    for (float side : {-0.5f, 0.5f}) {
      Vec3 p, u, v;
      p[axis] = side;
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      p[a] = p[b] = -0.5f;
      u[a] = 1;
      v[b] = 1;
      if (side < 0) {  // cross(u, v) points along +axis: swap to face outwards
        Vec3 t = u;
        u = v;
        v = t;
      }
      add_parallelogram(mesh, p, u, v);
    }
  }
  transform_mesh(mesh, to_world);
  return mesh;
}

TriangleMesh quad_mesh(Vec3 corner, Vec3 u, Vec3 v, const Affine& to_world) {
  TriangleMesh mesh;
  add_parallelogram(mesh, corner, u, v);
  transform_mesh(mesh, to_world);
  return mesh;
}

TriangleMesh ellipsoid_mesh(Vec3 center, float radius, const Affine& to_world) {
  TriangleMesh mesh;
  constexpr int kCols = kEllipsoidSegments + 1;  // the seam column is repeated
  for (int i = 0; i <= kEllipsoidRings; ++i) {
    const double theta = std::numbers::pi * i / kEllipsoidRings;  // from the +y pole
    for (int j = 0; j < kCols; ++j) {
      const double phi = 2 * std::numbers::pi * (j % kEllipsoidSegments) / kEllipsoidSegments;
      const Vec3 d{float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)),
                   float(-std::sin(theta) * std::sin(phi))};
      mesh.positions.push_back(center + radius * d);
      mesh.normals.push_back(d);
    }
  }
  for (int i = 0; i < kEllipsoidRings; ++i) {
    for (int j = 0; j < kEllipsoidSegments; ++j) {
      const auto a = std::uint32_t(i * kCols + j), b = a + 1, c = a + kCols + 1, d = a + kCols;
      // The rings at the poles are single points: one triangle per segment there.
      if (i != 0) mesh.triangles.push_back({a, d, b});
      if (i != kEllipsoidRings - 1) mesh.triangles.push_back({b, d, c});
    }
  }
  transform_mesh(mesh, to_world);
  return mesh;
}

TriangleMesh ellipse_mesh(Vec3 center, Vec3 normal, float radius, const Affine& to_world) {
  TriangleMesh mesh;
  Vec3 a, b;
  orthonormal_basis(normal, a, b);
  mesh.positions.push_back(center);
  for (int k = 0; k < kEllipseSegments; ++k) {
    const double phi = 2 * std::numbers::pi * k / kEllipseSegments;
    mesh.positions.push_back(center + a * float(radius * std::cos(phi)) +
                             b * float(radius * std::sin(phi)));
  }
  mesh.normals.assign(mesh.positions.size(), normal);
  for (int k = 0; k < kEllipseSegments; ++k)
    mesh.triangles.push_back(
        {0, std::uint32_t(1 + k), std::uint32_t(1 + (k + 1) % kEllipseSegments)});
  transform_mesh(mesh, to_world);
  return mesh;
}

}  // namespace penumbra::spaceland
