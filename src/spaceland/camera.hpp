// The format's pinhole camera: the one definition of the ray through pixel (i, j), and the
// sky's radiance by direction. Every 3D method starts its camera rays here.
#pragma once

#include <cmath>

#include "core/math.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/embree/ray_scene.hpp"

namespace penumbra::spaceland {

class CameraRays {
 public:
  explicit CameraRays(const Camera& c)
      : origin_(c.position),
        width_(c.width),
        height_(c.height),
        t_(std::tan(double(c.fov_y) * kPi / 360)) {
    const Vec3 f = normalize(c.look_at - c.position);
    const Vec3 r = normalize(cross(f, c.up));
    f_ = f;
    r_ = r;
    u_ = cross(r, f);
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

 private:
  Vec3 origin_, f_, r_, u_;
  int width_, height_;
  double t_;
};

// The sky's radiance in unit direction d, without the sun.
inline Rgb sky_radiance(const Sky& s, Vec3 d) {
  if (d.y < 0) return s.ground;
  const float y = d.y;
  return {s.horizon.r + (s.zenith.r - s.horizon.r) * y,
          s.horizon.g + (s.zenith.g - s.horizon.g) * y,
          s.horizon.b + (s.zenith.b - s.horizon.b) * y};
}

// What a ray that leaves the scene sees: the sky, and the sun's disk where it lies. The sun's
// direction, extent and radiance are worked out once, since methods ask for every ray.
class Background {
 public:
  explicit Background(const Scene& scene) : sky_(scene.sky) {
    const Sun& sun = scene.sun;
    if (!scene.has_sun || (sun.irradiance.r <= 0 && sun.irradiance.g <= 0 && sun.irradiance.b <= 0))
      return;
    has_sun_ = true;
    dir_ = normalize(sun.direction);
    const double a = double(sun.angular_radius) * kPi / 180, sr = std::sin(a);
    cos_radius_ = std::cos(a);
    one_minus_cos_ = sr * sr / (1 + cos_radius_);  // 1 - cos without cancellation
    // irradiance / (pi sin^2(angular radius)): a uniform disk that gives the irradiance.
    const double k = 1 / (kPi * sr * sr);
    sun_ = {float(sun.irradiance.r * k), float(sun.irradiance.g * k), float(sun.irradiance.b * k)};
  }

  Rgb sky(Vec3 d) const { return sky_radiance(sky_, d); }
  bool has_sun() const { return has_sun_; }
  // Whether unit direction d lies in the sun's disk.
  bool in_sun(Vec3 d) const { return has_sun_ && double(dot(d, dir_)) >= cos_radius_; }
  Rgb sun() const { return sun_; }             // radiance inside the disk
  Vec3 sun_direction() const { return dir_; }  // unit, towards the sun
  double sun_one_minus_cos() const { return one_minus_cos_; }

  Rgb operator()(Vec3 d) const {
    Rgb c = sky(d);
    if (in_sun(d)) c = {c.r + sun_.r, c.g + sun_.g, c.b + sun_.b};
    return c;
  }

 private:
  Sky sky_;
  bool has_sun_ = false;
  Vec3 dir_{0, 1, 0};
  double cos_radius_ = 1, one_minus_cos_ = 0;
  Rgb sun_{};
};

}  // namespace penumbra::spaceland
