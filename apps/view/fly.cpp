#include "view/fly.hpp"

#include <algorithm>
#include <cmath>

using penumbra::Vec3;

namespace viewer {

namespace {

constexpr float kDegrees = 3.14159265358979323846f / 180;
constexpr float kMaxPitch = 89;

Vec3 unit(Vec3 v) {
  const float n = std::sqrt(dot(v, v));
  return n > 0 ? v * (1 / n) : v;
}

}  // namespace

Fly Fly::from(const penumbra::spaceland::Camera& c) {
  Fly f;
  f.position = c.position;
  f.up = unit(c.up);
  const Vec3 d = unit(c.look_at - c.position);
  // The heading's zero: the view direction flattened onto the plane normal to up (the scene
  // format refuses a view parallel to up, so it is not zero).
  f.reference = unit(d - f.up * dot(d, f.up));
  f.yaw = 0;
  f.pitch = std::clamp(std::asin(std::clamp(dot(d, f.up), -1.0f, 1.0f)) / kDegrees, -kMaxPitch,
                       kMaxPitch);
  return f;
}

Vec3 Fly::forward() const {
  const Vec3 side = cross(reference, up);  // reference turned 90 degrees to the right
  const float y = yaw * kDegrees, p = pitch * kDegrees;
  const Vec3 flat = reference * std::cos(y) + side * std::sin(y);
  return unit(flat * std::cos(p) + up * std::sin(p));
}

Vec3 Fly::right() const {
  return unit(cross(forward(), up));
}

void Fly::move(Vec3 d) {
  position = position + right() * d.x + up * d.y + forward() * d.z;
}

void Fly::turn(float yaw_degrees, float pitch_degrees) {
  yaw = std::remainder(yaw + yaw_degrees, 360.0f);
  pitch = std::clamp(pitch + pitch_degrees, -kMaxPitch, kMaxPitch);
}

penumbra::spaceland::Camera Fly::camera(const penumbra::spaceland::Camera& base) const {
  penumbra::spaceland::Camera c = base;
  c.position = position;
  // look_at as far ahead as the position is from the origin (at least a unit), so that its
  // floats keep the direction's precision far from the origin.
  const float ahead = std::max(1.0f, std::sqrt(dot(position, position)));
  c.look_at = position + forward() * ahead;
  c.up = up;
  return c;
}

}  // namespace viewer
