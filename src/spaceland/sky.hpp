// What a ray that leaves the scene sees: the format's sky by direction, and the sun's disk.
#pragma once

#include <cmath>

#include "core/fnv.hpp"
#include "core/math.hpp"
#include "penumbra/spaceland/scene.hpp"

namespace penumbra::spaceland {

// Feeds `f` the scene's sky and, with `sun`, whether it has a sun and its light: the part of a
// scene's fingerprint that lights it from outside.
inline void hash_light(Fnv1a& f, const Scene& s, bool sun = true) {
  f.value(s.sky.zenith);
  f.value(s.sky.horizon);
  f.value(s.sky.ground);
  if (!sun) return;
  f.value(s.has_sun);
  if (s.has_sun) {
    f.value(s.sun.direction);
    f.value(s.sun.irradiance);
    f.value(s.sun.angular_radius);
  }
}

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
