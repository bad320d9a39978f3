// The emitters a 3D method aims at: emitting triangles, spheres and disks (picked by power,
// sampled by solid angle where that is cheap, by area otherwise) and the sun (its cone). One
// definition of each sampling pdf, so that multiple importance sampling weights agree with it.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "penumbra/spaceland/scene.hpp"
#include "spaceland/ray.hpp"
#include "spaceland/sky.hpp"

namespace penumbra::spaceland {

// A point on an emitter seen from a shading point.
struct LightSample {
  Vec3 direction;  // unit, from the shading point
  float distance;  // to the sampled point
  Vec3 point;      // on the emitter
  Vec3 normal;     // the emitter's geometric normal there
  Rgb radiance{};  // emitted towards the shading point
  float pdf = 0;   // solid-angle density, the pick included (0: no sample)
  // Which emitter (for the sun: none): a shadow ray that first meets this very primitive has
  // reached the light, even if it meets it a hair before the sampled point (a grazing ray on a
  // sphere's rim).
  bool sun = false;
  ShapeKind kind = ShapeKind::triangle;
  std::uint32_t shape = 0, primitive = 0;

  bool is(const Hit& h) const {
    return !sun && h.kind == kind && h.shape == shape &&
           (kind != ShapeKind::triangle || h.primitive == primitive);
  }
};

class Lights {
 public:
  explicit Lights(const Scene& scene);

  bool empty() const { return emitters_.empty(); }
  std::size_t size() const { return emitters_.size(); }

  // Picks an emitter by power with `u_pick` and a point on it with `u`.
  LightSample sample(Vec3 p, float u_pick, std::array<float, 2> u) const;
  // Density sample() would have given to reaching `hit` (an emitter) from p, in solid angle.
  float pdf(Vec3 p, const Hit& hit) const;

  // The sun's cone, when the scene has a sun.
  bool has_sun() const { return background_.has_sun(); }
  LightSample sample_sun(std::array<float, 2> u) const;
  float sun_pdf() const { return sun_pdf_; }
  // The sky and the sun as rays that leave the scene see them.
  const Background& background() const { return background_; }

  std::uint64_t bytes() const;

 private:
  struct Emitter {
    ShapeKind kind;
    std::uint32_t shape, primitive;
    float area;
    Rgb emission;
  };
  int index_of(const Hit& hit) const;
  float pick_probability(int e) const;
  float solid_angle_pdf(const Emitter& e, Vec3 p, Vec3 q, Vec3 n) const;

  const Scene* scene_;
  std::vector<Emitter> emitters_;
  std::vector<double> cdf_;  // cumulative power, normalised to end at 1
  // Emitter index per triangle of each mesh (empty for meshes that do not emit), per sphere,
  // per disk; -1 where none.
  std::vector<std::vector<int>> triangle_emitter_;
  std::vector<int> sphere_emitter_, disk_emitter_;

  Background background_;
  Vec3 sun_t_, sun_b_;  // a basis around the sun's direction, for sampling its cone
  float sun_pdf_ = 0;
};

}  // namespace penumbra::spaceland
