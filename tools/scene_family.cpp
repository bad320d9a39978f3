// Writes a family of random 3D scenes of the kinds users make and our example scenes are not
// (issue 35), for the quality study of docs/QUALITY.md ("The scene family"):
//   penumbra_scene_family OUT [--count N] [--seed S] [--width W] [--height H]
// writes N scenes of each class into OUT:
//   night_K.json  a ground of radius 50-100 at night, 1-3 sphere lights of radius 0.05-0.3 (one
//                 in view, one behind the camera when there are two or more) among meshes;
//   behind_K.json a closed room lit only by a panel on the wall behind the camera, meshes inside;
//   window_K.json a closed room lit by the sun and the sky through one window.
// The meshes are Debian's: glmark2-data's bunny and assimp-testmodels' textured box. The same
// seed writes the same bytes: integer hashing, no <random> distributions.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "io/image_io.hpp"
#include "tool_cli.hpp"

namespace {

using nlohmann::ordered_json;
using V = std::array<double, 3>;

// Uniform numbers from a counter-based hash (the same on every machine).
struct Dice {
  std::uint64_t state;
  double uniform(double lo, double hi) {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return lo + (hi - lo) * double(z >> 11) * 0x1.0p-53;
  }
  int pick(int n) { return std::min(n - 1, int(uniform(0, n))); }
};

// Rounded to 3 decimals, so that the files read well.
double r3(double v) {
  return double(std::int64_t(v * 1000 + (v < 0 ? -0.5 : 0.5))) / 1000;
}
ordered_json vec(V v) {
  return ordered_json::array({r3(v[0]), r3(v[1]), r3(v[2])});
}
ordered_json quad(V corner, V u, V v, const char* material) {
  return {{"type", "quad"},
          {"corner", vec(corner)},
          {"u", vec(u)},
          {"v", vec(v)},
          {"material", material}};
}

constexpr const char* kBunny = "/usr/share/glmark2/models/bunny.obj";
constexpr const char* kBox = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf";

// One to three objects on the floor within `spread` of (cx, cz): the bunny, the textured box, a
// box or a sphere, turned at random.
void add_meshes(Dice& d, ordered_json& objects, double cx, double cz, double spread) {
  const int n = 1 + d.pick(3);
  for (int i = 0; i < n; ++i) {
    const double x = cx + d.uniform(-spread, spread), z = cz + d.uniform(-spread, spread);
    const double turn = r3(d.uniform(0, 360));
    switch (d.pick(4)) {
      case 0:  // the bunny's feet at y = 0
        objects.push_back(
            {{"type", "mesh"},
             {"file", kBunny},
             {"material", "matte"},
             {"transform", {{"rotate", {0, turn, 0}}, {"translate", vec({x, 0.991233, z})}}}});
        break;
      case 1:
        objects.push_back(
            {{"type", "mesh"},
             {"file", kBox},
             {"transform", {{"rotate", {0, turn, 0}}, {"translate", vec({x, 0.5, z})}}}});
        break;
      case 2: {
        const double h = d.uniform(0.4, 1.6);
        objects.push_back({{"type", "box"},
                           {"center", vec({x, h / 2, z})},
                           {"size", vec({d.uniform(0.3, 1.2), h, d.uniform(0.3, 1.2)})},
                           {"rotate", {0, turn, 0}},
                           {"material", "tinted"}});
        break;
      }
      default: {
        const double r = d.uniform(0.2, 0.6);
        objects.push_back({{"type", "sphere"},
                           {"center", vec({x, r, z})},
                           {"radius", r3(r)},
                           {"material", "matte"}});
      }
    }
  }
}

ordered_json materials(Dice& d) {
  const double g = d.uniform(0.4, 0.7);
  return {{"ground", {{"albedo", vec({g, g, g})}}},
          {"matte", {{"albedo", vec({0.75, 0.72, 0.68})}}},
          {"tinted",
           {{"albedo", vec({d.uniform(0.2, 0.8), d.uniform(0.2, 0.8), d.uniform(0.2, 0.8)})}}}};
}

ordered_json camera(V position, V look_at, int w, int h, double fov) {
  return {{"position", vec(position)},
          {"look_at", vec(look_at)},
          {"fov_y", r3(fov)},
          {"width", w},
          {"height", h}};
}

ordered_json scene(const std::string& description, ordered_json camera, ordered_json materials,
                   ordered_json objects) {
  return {{"penumbra", 1},
          {"dimensions", 3},
          {"description", description},
          {"camera", std::move(camera)},
          {"materials", std::move(materials)},
          {"objects", std::move(objects)}};
}

// A sphere light of radius 0.05-0.3 whose power does not depend on its size (Le r^2 from 2 to 6).
void add_light(Dice& d, ordered_json& objects, ordered_json& mats, const std::string& name,
               V centre) {
  const double r = d.uniform(0.05, 0.3), le = d.uniform(2, 6) / (r * r);
  mats[name] = {{"emission", vec({le, le * 0.85, le * 0.6})}};
  objects.push_back(
      {{"type", "sphere"}, {"center", vec(centre)}, {"radius", r3(r)}, {"material", name}});
}

ordered_json night(Dice& d, int w, int h) {
  ordered_json mats = materials(d), objects = ordered_json::array();
  const double ground = d.uniform(50, 100);
  objects.push_back({{"type", "disk"},
                     {"center", vec({0, 0, 0})},
                     {"normal", vec({0, 1, 0})},
                     {"radius", r3(ground)},
                     {"material", "ground"}});
  add_meshes(d, objects, 0, 0, 2);
  const V eye{d.uniform(-2, 2), d.uniform(1.2, 3), d.uniform(5, 7)};
  const int lights = 1 + d.pick(3);
  for (int i = 0; i < lights; ++i) {
    // The first in view, the second behind the camera, a third anywhere near.
    const V at = i == 0 ? V{d.uniform(-1.5, 1.5), d.uniform(0.5, 2), d.uniform(-1.5, 1.5)}
                 : i == 1
                     ? V{eye[0] + d.uniform(-1, 1), d.uniform(0.5, 2.5), eye[2] + d.uniform(1, 3)}
                     : V{d.uniform(-4, 4), d.uniform(0.5, 2.5), d.uniform(-4, 4)};
    add_light(d, objects, mats, "lamp" + std::to_string(i), at);
  }
  return scene("Night: a ground of radius " + std::to_string(int(ground)) + ", " +
                   std::to_string(lights) + " sphere light(s), one in view" +
                   (lights > 1 ? " and one behind the camera" : ""),
               camera(eye, {0, 0.5, 0}, w, h, d.uniform(40, 60)), mats, objects);
}

// The walls of a room [-sx, sx] x [0, sy] x [-sz, sz], facing in; the wall at x = +sx with a
// window (its opening's y and z ranges) when `window` is set. Each wall runs 0.05 past the
// corners into its neighbours: quads that only meet at an edge let rays through the crack
// (separate meshes are not watertight between them), which the path tracer shows as dotted
// lines of sunlight along the room's edges.
void add_room(ordered_json& objects, double sx, double sy, double sz, const double* window) {
  constexpr double m = 0.05;
  auto quad = [&](V corner, V u, V v, const char* material) {
    // Grown by m at both ends of u and v (each along one axis: its length is the sum of |.|).
    V c = corner, uu = u, vv = v;
    const double lu = std::abs(u[0]) + std::abs(u[1]) + std::abs(u[2]);
    const double lv = std::abs(v[0]) + std::abs(v[1]) + std::abs(v[2]);
    for (int a = 0; a < 3; ++a) {
      const double du = lu > 0 ? u[std::size_t(a)] / lu : 0,
                   dv = lv > 0 ? v[std::size_t(a)] / lv : 0;
      c[std::size_t(a)] -= m * (du + dv);
      uu[std::size_t(a)] += 2 * m * du;
      vv[std::size_t(a)] += 2 * m * dv;
    }
    return ::quad(c, uu, vv, material);
  };
  objects.push_back(quad({-sx, 0, -sz}, {0, 0, 2 * sz}, {2 * sx, 0, 0}, "ground"));  // floor
  objects.push_back(quad({-sx, sy, -sz}, {2 * sx, 0, 0}, {0, 0, 2 * sz}, "matte"));  // ceiling
  objects.push_back(quad({-sx, 0, -sz}, {2 * sx, 0, 0}, {0, sy, 0}, "matte"));       // back
  objects.push_back(quad({-sx, 0, sz}, {0, sy, 0}, {2 * sx, 0, 0}, "matte"));        // front
  objects.push_back(quad({-sx, 0, -sz}, {0, sy, 0}, {0, 0, 2 * sz}, "tinted"));      // left
  if (!window) {
    objects.push_back(quad({sx, 0, -sz}, {0, 0, 2 * sz}, {0, sy, 0}, "matte"));
    return;
  }
  const double y0 = window[0], y1 = window[1], z0 = window[2], z1 = window[3];
  objects.push_back(quad({sx, 0, -sz}, {0, 0, 2 * sz}, {0, y0, 0}, "matte"));         // below
  objects.push_back(quad({sx, y1, -sz}, {0, 0, 2 * sz}, {0, sy - y1, 0}, "matte"));   // above
  objects.push_back(quad({sx, y0, -sz}, {0, 0, z0 + sz}, {0, y1 - y0, 0}, "matte"));  // beside
  objects.push_back(quad({sx, y0, z1}, {0, 0, sz - z1}, {0, y1 - y0, 0}, "matte"));
}

ordered_json behind(Dice& d, int w, int h) {
  ordered_json mats = materials(d), objects = ordered_json::array();
  const double sx = d.uniform(2.5, 4), sy = d.uniform(2.4, 3.2), sz = d.uniform(2.5, 4);
  add_room(objects, sx, sy, sz, nullptr);
  add_meshes(d, objects, 0, -0.5, std::min(sx, sz) - 1.2);
  // The camera near the front wall looking at the back; the panel on the front wall above it.
  const V eye{d.uniform(-0.5, 0.5), d.uniform(1.2, 1.8), sz - 0.6};
  const double pw = d.uniform(0.6, 1.6), ph = d.uniform(0.4, 1.0), le = d.uniform(4, 12);
  mats["panel"] = {{"emission", vec({le, le * 0.9, le * 0.75})}};
  objects.push_back(quad({-pw / 2, sy - ph - 0.2, sz - 0.01}, {0, ph, 0}, {pw, 0, 0}, "panel"));
  return scene("A closed room lit only by a panel behind the camera",
               camera(eye, {0, 0.8, -sz}, w, h, 60), mats, objects);
}

ordered_json window(Dice& d, int w, int h) {
  ordered_json mats = materials(d), objects = ordered_json::array();
  const double sx = d.uniform(2.5, 4), sy = d.uniform(2.4, 3.2), sz = d.uniform(2.5, 4);
  const double wy0 = d.uniform(0.6, 1.0), wy1 = std::min(sy - 0.3, wy0 + d.uniform(0.8, 1.4));
  const double wz0 = d.uniform(-sz + 0.5, 0), wz1 = std::min(sz - 0.5, wz0 + d.uniform(0.8, 2));
  const double opening[4] = {wy0, wy1, wz0, wz1};
  add_room(objects, sx, sy, sz, opening);
  add_meshes(d, objects, -0.5, 0, std::min(sx, sz) - 1.2);
  const V eye{-sx + 0.6, d.uniform(1.2, 1.8), d.uniform(-1, 1)};
  ordered_json s = scene("A closed room lit by the sun and the sky through one window",
                         camera(eye, {sx, 0.8, d.uniform(-1, 1)}, w, h, 65), mats, objects);
  s["sky"] = {{"zenith", vec({0.3, 0.5, 1.0})},
              {"horizon", vec({0.8, 0.9, 1.0})},
              {"ground", vec({0.2, 0.2, 0.2})}};
  // The sun low enough to shine in through the window onto the floor.
  s["sun"] = {{"direction", vec({1, d.uniform(0.5, 1.0), d.uniform(-0.4, 0.4)})},
              {"irradiance", vec({6, 5.5, 5})},
              {"angular_radius", 0.27}};
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Writes the random 3D scene family of the quality study (docs/QUALITY.md)",
               "penumbra_scene_family"};
  std::string out;
  int count = 4, width = 160, height = 120;
  std::uint64_t seed = 35;
  app.add_option("folder", out, "Folder to write the scenes into")->required();
  app.add_option("--count", count, "Scenes of each class")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--seed", seed, "Seed (the same seed, the same files)")->capture_default_str();
  app.add_option("--width", width, "Image width")
      ->check(CLI::Range(1, 8192))
      ->capture_default_str();
  app.add_option("--height", height, "Image height")
      ->check(CLI::Range(1, 8192))
      ->capture_default_str();
  if (auto code = penumbra::tool::parse(app, argc, argv)) return *code;
  if (!penumbra::tool::output_folder("penumbra_scene_family", out))
    return penumbra::tool::kCannotWrite;
  std::vector<std::pair<std::string, std::string>> files;
  using Make = ordered_json (*)(Dice&, int, int);
  const std::pair<const char*, Make> classes[] = {
      {"night", night}, {"behind", behind}, {"window", window}};
  for (std::size_t c = 0; c < std::size(classes); ++c)
    for (int k = 0; k < count; ++k) {
      Dice d{seed * 1000003ull + c * 7919ull + std::uint64_t(k)};
      const std::string path = (std::filesystem::path(out) /
                                (std::string(classes[c].first) + "_" + std::to_string(k) + ".json"))
                                   .string();
      files.emplace_back(path, classes[c].second(d, width, height).dump(1) + "\n");
    }
  if (penumbra::Status s = penumbra::io::write_text_files(files); !s) {
    std::fprintf(stderr, "penumbra_scene_family: %s\n", s.error().message.c_str());
    return penumbra::tool::kCannotWrite;
  }
  std::printf("wrote %zu scenes into %s\n", files.size(), out.c_str());
  return 0;
}
