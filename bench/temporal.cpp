// Temporal reuse in a Renderer: ssrc's or spwi's accumulation, or the grid solved a few slabs a
// frame (--method grid --grid-slabs K) (RenderOptions::temporal; docs/VIEWER.md,
// "Temporal reuse"): how fast a new view converges and what a moving camera or sun leaves behind,
// against the path tracer. Phase 1 renders a still view `--run` frames; phase 2 turns the camera
// about its look_at (`--orbit`, degrees about the world's y) and the sun (`--sun-turn`) over
// `--steps` frames and holds the new view `--run` frames more. Every frame's relative RMSE against
// the path-traced reference of its phase's end view is printed, beside the same renders without
// temporal reuse (each frame then is render()'s).
//
//   penumbra_temporal SCENE.json [--method ssrc|spwi|grid] [--frames 16] [--grid-slabs 8]
//                     [--run 32] [--orbit 10] [--sun-turn 0] [--steps 8] [--spp 1024]
//                     [--width 160] [--bounces 1]
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "core/math.hpp"
#include "penumbra/compare.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "tool_cli.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::spaceland;

// `v` turned by `degrees` about the world's y axis.
Vec3 turn(Vec3 v, double degrees) {
  const double a = degrees * kPi / 180, c = std::cos(a), s = std::sin(a);
  return {float(c * v.x + s * v.z), v.y, float(-s * v.x + c * v.z)};
}

// The scene at fraction t of the move: the camera orbited about its look_at, the sun turned.
Scene moved(const Scene& base, double orbit, double sun_turn, double t) {
  Scene s = base;
  const Vec3 at = base.camera.look_at;
  s.camera.position = at + turn(base.camera.position - at, orbit * t);
  s.sun.direction = turn(base.sun.direction, sun_turn * t);
  return s;
}

ImageRgb reference(const Scene& scene, int spp, int bounces) {
  RenderOptions o;
  o.method = Method::pt;
  o.pt.spp = spp;
  o.bounces = bounces;
  Expected<RenderResult> r = render(scene, o);
  if (!r) {
    std::fprintf(stderr, "reference: %s\n", r.error().message.c_str());
    std::exit(1);
  }
  return std::move(r->radiance);
}

double error(const ImageRgb& test, const ImageRgb& ref) {
  Expected<ErrorMetrics> m = compare_images(test, ref);
  if (!m) {
    std::fprintf(stderr, "%s\n", m.error().message.c_str());
    std::exit(1);
  }
  return m->relative_rmse;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Temporal reuse (ssrc's and spwi's accumulation, the grid's slabs): convergence and "
      "ghosting against the path tracer",
      "penumbra_temporal"};
  std::string path, method = "ssrc";
  int frames = 16, slabs = 8, run = 32, steps = 8, spp = 1024, width = 160, bounces = 1;
  double orbit = 10, sun_turn = 0;
  app.add_option("scene", path, "A 3D scene")->required();
  app.add_option("--method", method, "The method accumulated")
      ->check(CLI::IsMember({"ssrc", "spwi", "grid"}))
      ->capture_default_str();
  app.add_option("--frames", frames, "The history's length (RenderOptions::temporal.frames)")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app.add_option("--grid-slabs", slabs,
                 "grid: slabs solved a frame (RenderOptions::temporal.grid_slabs)")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  app.add_option("--run", run, "Frames of each still view")->check(CLI::Range(1, 4096));
  app.add_option("--orbit", orbit, "The camera's turn about its look_at, degrees")
      ->capture_default_str();
  app.add_option("--sun-turn", sun_turn, "The sun's turn about the y axis, degrees");
  app.add_option("--steps", steps, "Frames the move takes")->check(CLI::Range(1, 4096));
  app.add_option("--bounces", bounces, "Bounces, of the method and the references")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  app.add_option("--spp", spp, "The references' samples per pixel")->check(CLI::Range(1, 1 << 20));
  app.add_option("--width", width, "The image's width (the height keeps the scene's aspect)")
      ->check(CLI::Range(8, 4096));
  if (const std::optional<int> stop = penumbra::tool::parse(app, argc, argv)) return *stop;

  Expected<Scene> loaded = load_scene(path);
  if (!loaded) {
    std::fprintf(stderr, "%s\n", loaded.error().message.c_str());
    return 1;
  }
  Scene a = *loaded;
  a.camera.height = std::max(1, int(std::lround(double(a.camera.height) * width / a.camera.width)));
  a.camera.width = width;
  const Scene b = moved(a, orbit, sun_turn, 1);
  const ImageRgb ref_a = reference(a, spp, bounces), ref_b = reference(b, spp, bounces);

  RenderOptions on, off;
  on.bounces = off.bounces = bounces;
  on.method = off.method = method == "spwi"   ? Method::spwi
                           : method == "grid" ? Method::grid
                                              : Method::ssrc;
  if (on.method == Method::grid)
    on.temporal.grid_slabs = slabs;
  else
    on.temporal.frames = frames;
  Renderer with, without;
  std::printf("| frame | view | relative RMSE, temporal | without | ms, temporal | without |\n");
  std::printf("| ---: | --- | ---: | ---: | ---: | ---: |\n");
  int frame = 0;
  const auto step = [&](const Scene& s, const ImageRgb* ref, const char* view) {
    Expected<RenderResult> t = with.render(s, on), u = without.render(s, off);
    if (!t || !u) {
      std::fprintf(stderr, "%s\n", (!t ? t.error() : u.error()).message.c_str());
      std::exit(1);
    }
    // The grid's solve under way: the frame shows the last grid solved.
    std::string what = view;
    if (t->grid_slabs > 0)
      what += " (slabs " + std::to_string(t->grid_slabs_done) + " of " +
              std::to_string(t->grid_slabs) + ")";
    if (ref)
      std::printf("| %d | %s | %.4f | %.4f | %.1f | %.1f |\n", frame, what.c_str(),
                  error(t->radiance, *ref), error(u->radiance, *ref), t->time_ms, u->time_ms);
    else
      std::printf("| %d | %s | | | %.1f | %.1f |\n", frame, what.c_str(), t->time_ms, u->time_ms);
    ++frame;
  };
  for (int f = 0; f < run; ++f) step(a, &ref_a, "still A");
  for (int f = 1; f < steps; ++f)
    step(moved(a, orbit, sun_turn, double(f) / steps), nullptr, "moving");
  for (int f = 0; f < run; ++f) step(b, &ref_b, "still B");
  return 0;
}
