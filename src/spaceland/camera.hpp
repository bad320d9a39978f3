// The format's pinhole camera: the one definition of the ray through pixel (i, j). Every 3D
// method starts its camera rays here.
#pragma once

#include <cmath>

#include "core/d3.hpp"
#include "core/math.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/ray.hpp"

namespace penumbra::spaceland {

class CameraRays {
 public:
  explicit CameraRays(const Camera& c)
      : origin_(c.position),
        width_(c.width),
        height_(c.height),
        t_(std::tan(double(c.fov_y) * kPi / 360)) {
    // In double: a view direction or an `up` of length 1e-30 squares to nothing in float.
    const D3 f = normalize_scaled(d3(c.look_at) - d3(c.position));
    const D3 r = normalize_scaled(cross(f, normalize_scaled(d3(c.up))));
    f_ = f3(f);
    r_ = f3(r);
    u_ = f3(cross(r, f));
  }

  // Unit direction of pixel (i, j), row 0 at the top; computed in double so that the spec's
  // formula is met to float rounding.
  Vec3 direction(int i, int j) const {
    const double x = (2 * (i + 0.5) / width_ - 1) * t_ * width_ / height_;
    const double y = (1 - 2 * (j + 0.5) / height_) * t_;
    const double d[3] = {f_.x + x * r_.x + y * u_.x, f_.y + x * r_.y + y * u_.y,
                         f_.z + x * r_.z + y * u_.z};
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    return {float(d[0] / len), float(d[1] / len), float(d[2] / len)};
  }
  Ray ray(int i, int j) const { return Ray{origin_, direction(i, j), 0.0f, 3.0e38f}; }
  Vec3 forward() const { return f_; }
  Vec3 origin() const { return origin_; }
  Vec3 right() const { return r_; }  // the image's x axis in the world
  Vec3 up() const { return u_; }     // its y axis, upwards (pixel rows run down)
  double tan_half_fov() const { return t_; }

 private:
  Vec3 origin_, f_, r_, u_;
  int width_, height_;
  double t_;
};

}  // namespace penumbra::spaceland
