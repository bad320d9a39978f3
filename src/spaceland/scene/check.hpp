// The rules a 3D scene obeys, shared by the document parser (scene_json.cpp) and check_scene:
// failures throw io::JsonFailure "<file>: <path>: <what>", the parser's message form.
#pragma once

#include <cmath>
#include <string>

#include "penumbra/spaceland/scene.hpp"

namespace penumbra::spaceland {

// "[1, 0, -2.5]", for messages.
std::string format_vec3(Vec3 v);

// The camera's relations: look_at distinct from position, up not parallel to the view direction
// (ranges included, so that a scene built in code is checked too).
void check_camera(const std::string& file, const Camera& camera);

// Whether a point lies within kMaxCoordinate of the origin on every axis (false for NaN).
inline bool inside_world(Vec3 p) {
  return std::fabs(p.x) <= kMaxCoordinate && std::fabs(p.y) <= kMaxCoordinate &&
         std::fabs(p.z) <= kMaxCoordinate;
}

// The box [lo, hi] of an object lies within kMaxCoordinate of the origin on every axis; `what`
// says what reaches past it ("the sphere", "vertex 3 of the file, after the transform").
void check_within_world(const std::string& file, const std::string& path, Vec3 lo, Vec3 hi,
                        const std::string& what);

// Every rule of check_scene, throwing.
void check_scene_or_throw(const Scene& scene);

}  // namespace penumbra::spaceland
