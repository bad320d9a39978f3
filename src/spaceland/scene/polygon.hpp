// Triangulating an OBJ face of any number of corners in time linear in its corners where it is
// convex (the usual case: a disk's cap, an n-gon), and corners x reflex corners otherwise.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "penumbra/vec3.hpp"

namespace penumbra::spaceland {

struct PolygonWork {
  std::uint64_t steps = 0;  // corners visited plus reflex corners tested
  bool convex = false;      // triangulated as a fan
};

// Appends triangles (indices into `corners`, in order around the polygon, which is planar or
// nearly so) that cover the polygon: a triangle as it is; a quad split along its shorter diagonal
// (as tinyobjloader splits it, so meshes read before read the same); a convex polygon (turning once
// around, every turn the same way) as a fan from its first corner; any other by ear clipping in its
// plane, testing only the reflex corners against each ear. A polygon with no ear left (it crosses
// itself) has its rest fanned. False, with nothing appended, when the clipping would take more than
// `max_steps` steps (work.steps says how many it took before it stopped).
bool triangulate_polygon(const std::vector<Vec3>& corners,
                         std::vector<std::array<std::uint32_t, 3>>& out, std::uint64_t max_steps,
                         PolygonWork& work);

}  // namespace penumbra::spaceland
