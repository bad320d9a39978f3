// Embedding libpenumbra in 3D: build a scene in code (a floor and a glowing sphere), path trace
// it, write a picture, and check one pixel against the closed form of a sphere light.
//
//   render_3d_in_code [output.png|.exr|.pfm]     (default: render_3d_in_code.png)
//
// Every call returns a Status or an Expected<T>; nothing is thrown across the API.
#include <cmath>
#include <cstdio>
#include <string>

#include "penumbra/penumbra.hpp"

namespace {

namespace sl = penumbra::spaceland;

int fail(const std::string& what) {
  std::fprintf(stderr, "render_3d_in_code: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  // One optional argument, the output file; anything that looks like an option gets the usage
  // (rather than becoming a file named "--help").
  const std::string output = argc > 1 ? argv[1] : "render_3d_in_code.png";
  if (argc > 2 || (!output.empty() && output[0] == '-')) {
    const bool help = argc == 2 && (output == "-h" || output == "--help");
    std::fprintf(help ? stdout : stderr, "usage: render_3d_in_code [output.png|.exr|.pfm]\n");
    return help ? 0 : 2;
  }

  sl::Scene scene;
  scene.source = "render_3d_in_code";
  // An odd image size puts a pixel centre on the view axis, through the point looked at.
  scene.camera.position = {0, 3, 3};
  scene.camera.look_at = {0, 0, 0};
  scene.camera.fov_y = 50;
  scene.camera.width = 161;
  scene.camera.height = 121;

  sl::Material floor;  // a grey Lambertian floor
  floor.albedo = {0.7f, 0.7f, 0.7f};
  sl::Material lamp;  // a glowing sphere that reflects nothing
  lamp.albedo = {0, 0, 0};
  lamp.emission = {8, 8, 8};
  scene.materials = {floor, lamp};
  scene.objects = {"floor (disk)", "lamp (sphere)"};  // one line per object, for messages

  sl::Disk ground;  // y = 0, normal up, material 0
  ground.radius = 100;
  ground.object = 0;
  scene.disks.push_back(ground);
  sl::Sphere bulb;
  bulb.center = {0, 1, 0};
  bulb.radius = 0.25f;
  bulb.material = 1;
  bulb.object = 1;
  scene.spheres.push_back(bulb);

  sl::RenderOptions options;  // the reference path tracer, direct light (1 bounce)
  options.pt.spp = 256;
  penumbra::Expected<sl::RenderResult> result = sl::render(scene, options);
  if (!result) return fail(result.error().message);

  if (penumbra::Status s = sl::write_images({output}, result->radiance, sl::Aov::radiance); !s)
    return fail(s.error().message);

  // The centre pixel sees the floor right under the sphere: L = albedo Le (r / d)^2.
  const penumbra::Rgb centre = result->radiance.at(80, 60);
  const double expected = 0.7 * 8 * std::pow(0.25 / 1.0, 2);
  std::printf("render_3d_in_code: %dx%d, %llu rays in %.1f ms; wrote %s\n", scene.camera.width,
              scene.camera.height, (unsigned long long)result->rays, result->time_ms,
              output.c_str());
  std::printf("  under the sphere: %.4f (closed form %.4f)\n", centre.g, expected);
  if (std::abs(centre.g / expected - 1) > 0.01) return fail("the floor under the sphere is off");
  return 0;
}
