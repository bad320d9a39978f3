#include "spaceland/brightness.hpp"

#include <cfloat>
#include <cmath>
#include <string>
#include <vector>

#include "core/math.hpp"
#include "io/json_reader.hpp"
#include "spaceland/surface.hpp"

namespace penumbra::spaceland {

namespace {

double largest(const Rgb& c) {
  return std::fmax(double(c.r), std::fmax(double(c.g), double(c.b)));
}
bool finite(const Rgb& c) {
  return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b);
}

// The document's path of a material's emission: its name is its key in `materials`, the path of
// a material written in place, or a mesh file's name for it (docs/scene-format.md).
std::string emission_path(const Material& m, std::size_t index) {
  if (m.name.empty()) return "materials[" + std::to_string(index) + "].emission";
  if (m.name.rfind("objects[", 0) == 0) return m.name + ".emission";
  return "materials." + m.name + ".emission";
}

struct Brightest {
  double value = 0;
  std::string where;
};

void consider(Brightest& b, double value, std::string where) {
  if (value > b.value) b = {value, std::move(where)};
}

// The largest radiance the scene can make: each bounce re-emits at most `albedo` of what arrives,
// so a surface's radiance is at most R (1 + a + ... + a^N) + E_sun / pi (a + ... + a^N), R the
// brightest emitter, sky or fog path, a the largest albedo; the sun's disk itself is seen too.
struct Bound {
  Brightest source;  // the brightest radiance R and where it is
  double sun_disk = 0, sun_irradiance = 0, albedo = 0, radiance = 0;
};

Expected<Bound> bound(const Scene& s, int bounces) {
  Bound b;
  const std::vector<char> used = materials_in_use(s);
  for (std::size_t i = 0; i < s.materials.size(); ++i) {
    const Material& m = s.materials[i];
    if (!finite(m.emission) || !finite(m.albedo))
      return Error{s.source + ": " + emission_path(m, i) + ": not finite"};
    if (!used[i]) continue;
    consider(b.source, largest(m.emission), emission_path(m, i));
    b.albedo = std::fmax(b.albedo, largest(m.albedo));
  }
  const char* sky_names[3] = {"sky.zenith", "sky.horizon", "sky.ground"};
  const Rgb sky[3] = {s.sky.zenith, s.sky.horizon, s.sky.ground};
  for (int k = 0; k < 3; ++k) {
    if (!finite(sky[k])) return Error{s.source + ": " + sky_names[k] + ": not finite"};
    consider(b.source, largest(sky[k]), sky_names[k]);
  }
  // A ray may cross every fog box before it meets a surface: their paths' emission adds to the
  // brightest surface or sky (named, where it is the larger part, by the brightest box).
  Brightest fog;
  double fog_sum = 0;
  for (std::size_t i = 0; i < s.media.size(); ++i) {
    const Medium& m = s.media[i];
    const std::string path = "media[" + std::to_string(i) + "]";
    if (!finite(m.emission) || !finite(m.albedo))
      return Error{s.source + ": " + path + ".emission: not finite"};
    // Emission per unit length along the longest path through the box, its diagonal.
    const double diagonal = 2 * std::sqrt(double(m.half_size.x) * m.half_size.x +
                                          double(m.half_size.y) * m.half_size.y +
                                          double(m.half_size.z) * m.half_size.z);
    fog_sum += largest(m.emission) * diagonal;
    consider(fog, largest(m.emission) * diagonal, path + ".emission");
    b.albedo = std::fmax(b.albedo, largest(m.albedo));
  }
  if (fog_sum > 0) {
    const std::string where = fog_sum > b.source.value ? fog.where : b.source.where;
    b.source = {b.source.value + fog_sum, where};
  }
  if (s.has_sun) {
    if (!finite(s.sun.irradiance)) return Error{s.source + ": sun.irradiance: not finite"};
    b.sun_irradiance = largest(s.sun.irradiance);
    const double sine = std::sin(double(s.sun.angular_radius) * kPi / 180);
    b.sun_disk = b.sun_irradiance / (kPi * sine * sine);
  }
  double reflected = 0, power = 1;  // a + ... + a^N
  for (int j = 1; j <= bounces; ++j) reflected += (power *= std::fmin(b.albedo, 1.0));
  b.radiance = b.source.value * (1 + reflected) + b.sun_irradiance / kPi * reflected;
  return b;
}

std::string rounded(double v) {
  return io::format_rounded(v);
}

}  // namespace

Expected<int> light_exponent(const Scene& s, int bounces) {
  Expected<Bound> got = bound(s, bounces);
  if (!got) return got.error();
  const Bound& b = *got;
  if (b.sun_disk > FLT_MAX)
    return Error{
        s.source + ": sun: the radiance of its disk, irradiance / (pi sin^2(angular_radius)) = " +
        rounded(b.sun_irradiance) + " / (pi sin^2(" + io::format_number(s.sun.angular_radius) +
        " degrees)) = " + rounded(b.sun_disk) + ", is more than a float holds (" +
        rounded(FLT_MAX) + "); widen its angular_radius or lower its irradiance"};
  if (b.radiance > FLT_MAX) {
    const std::string n = std::to_string(bounces);
    const std::string a = rounded(b.albedo);
    const bool sun = b.sun_irradiance / kPi > b.source.value;
    std::string sum = rounded(b.source.value) + " x (1 + " + a + " + ... + " + a + "^" + n + ")";
    if (s.has_sun)
      sum += " + " + rounded(b.sun_irradiance) + " / pi x (" + a + " + ... + " + a + "^" + n +
             ") from the sun";
    return Error{s.source + ": " + (sun ? std::string("sun.irradiance") : b.source.where) + ": " +
                 rounded(sun ? b.sun_irradiance : b.source.value) +
                 " is too bright to render: with albedo up to " + a + " the radiance can reach " +
                 sum + " = " + rounded(b.radiance) + " at " + n +
                 (bounces == 1 ? " bounce" : " bounces") + ", more than a float holds (" +
                 rounded(FLT_MAX) + "); scale the scene's emission, sky and sun down"};
  }
  const double peak = std::fmax(b.radiance, b.sun_disk);
  if (peak <= kLargestComputedRadiance) return 0;
  int k = int(std::ceil(std::log2(peak / kLargestComputedRadiance)));
  while (std::ldexp(peak, -k) > kLargestComputedRadiance) ++k;  // log2's rounding
  return k;
}

Scene dimmed(const Scene& scene, int exponent) {
  Scene s = scene;
  auto dim = [exponent](Rgb& c) {
    c = {std::ldexp(c.r, -exponent), std::ldexp(c.g, -exponent), std::ldexp(c.b, -exponent)};
  };
  for (Material& m : s.materials) dim(m.emission);
  dim(s.sky.zenith);
  dim(s.sky.horizon);
  dim(s.sky.ground);
  dim(s.sun.irradiance);
  for (Medium& m : s.media) dim(m.emission);
  return s;
}

}  // namespace penumbra::spaceland
