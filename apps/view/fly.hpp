// The viewer's fly camera: a position, a heading (yaw about the scene camera's up) and a pitch,
// and the scene Camera they make. Pure arithmetic, so that a replay moves it the same way on
// every machine.
#pragma once

#include "penumbra/spaceland/scene.hpp"

namespace viewer {

struct Fly {
  penumbra::Vec3 position;
  penumbra::Vec3 up{0, 1, 0};  // unit: the axis the heading turns about (the scene camera's up)
  float yaw = 0;               // degrees about `up`, from the reference direction below
  float pitch = 0;             // degrees above the plane normal to `up`, in (-89, 89)
  penumbra::Vec3 reference{0, 0, -1};  // unit, normal to `up`: the direction of yaw 0

  // Starts from a scene camera: its position, its view direction as yaw and pitch.
  static Fly from(const penumbra::spaceland::Camera& c);
  penumbra::Vec3 forward() const;
  penumbra::Vec3 right() const;  // normal to forward and up
  // Moves along right, up and forward by the given distances; turns by degrees (pitch held
  // within 89 degrees of the horizon).
  void move(penumbra::Vec3 right_up_forward);
  void turn(float yaw_degrees, float pitch_degrees);
  // The scene camera looking from here: look_at ahead (a unit, or as far as the position is from
  // the origin), fov and size from `base`.
  penumbra::spaceland::Camera camera(const penumbra::spaceland::Camera& base) const;
};

}  // namespace viewer
