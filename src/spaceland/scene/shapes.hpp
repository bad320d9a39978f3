// The analytic objects of the format as triangles: boxes, quads, and the spheres and disks that
// a non-uniform scale turns into ellipsoids and ellipses.
#pragma once

#include "penumbra/spaceland/scene.hpp"
#include "spaceland/scene/transform.hpp"

namespace penumbra::spaceland {

// Tessellation of ellipsoids (longitude x latitude) and ellipses (rim segments): fine enough
// that the flat facets deviate from the exact surface by about 3e-4 of the radius
// (1 - cos(pi / 128)), with smooth normals from the exact surface.
inline constexpr int kEllipsoidSegments = 128;
inline constexpr int kEllipsoidRings = 64;
inline constexpr int kEllipseSegments = 256;

// Each returns positions, normals (unit, flat for boxes and quads) and triangles in world space;
// `materials` and `object` are left for the caller.

// The unit cube [-0.5, 0.5]^3 through `to_world`: 24 positions (4 per face), 12 triangles.
TriangleMesh box_mesh(const Affine& to_world);
// corner + s u + t v, s, t in [0, 1], through `to_world`: 4 positions, 2 triangles.
TriangleMesh quad_mesh(Vec3 corner, Vec3 u, Vec3 v, const Affine& to_world);
// The sphere (center, radius) through `to_world`.
TriangleMesh ellipsoid_mesh(Vec3 center, float radius, const Affine& to_world);
// The disk (center, unit normal, radius) through `to_world`.
TriangleMesh ellipse_mesh(Vec3 center, Vec3 normal, float radius, const Affine& to_world);

// Positions and normals of `mesh` through `to_world`.
void transform_mesh(TriangleMesh& mesh, const Affine& to_world);

}  // namespace penumbra::spaceland
