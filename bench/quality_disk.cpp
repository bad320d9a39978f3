// Quality of radiance cascades and of the path tracer against the closed form of a disk light, F =
// 2 L asin(r / d), and against an exact reference on the same cell grid (many exact DDA rays per
// cell). Writes a markdown table on stdout and pictures (render, signed error) into the folder
// given.
//
//   build/bin/penumbra_quality docs/images > table.md
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "flatland/trace.hpp"
#include "io/image_io.hpp"
#include "penumbra/penumbra.hpp"
#include "tool_cli.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::flatland;

struct Disk {
  int n = 256;
  float cx = 128.3f, cy = 127.8f, r = 16, L = 2.5f;
  bool counted(int x, int y) const {
    const double px = x + 0.5, py = y + 0.5;
    return std::hypot(px - cx, py - cy) >= r + 4 && px >= 4 && py >= 4 && px <= n - 4 &&
           py <= n - 4;
  }
  double exact(int x, int y) const {
    return 2.0 * L * std::asin(r / std::hypot(x + 0.5 - cx, y + 0.5 - cy));
  }
};

// Exact fluence on the cell grid at every 4th cell: 8192 DDA rays over the full circle.
std::vector<double> grid_reference(const Disk& d, const Scene& s) {
  Medium m = make_medium(s);
  build_distance_field(m);
  std::vector<double> ref(std::size_t(d.n) * d.n, -1);
  parallel_for(d.n / 4, [&](int yy) {
    const int y = yy * 4 + 1;
    for (int x = 1; x < d.n; x += 4) {
      if (!d.counted(x, y)) continue;
      const int rays = 8192;
      double sum = 0;
      for (int k = 0; k < rays; ++k) {
        const double a = 2 * kPi * (k + 0.5) / rays;
        sum += trace_interval(m, x + 0.5f, y + 0.5f, float(std::cos(a)), float(std::sin(a)), 0,
                              1e5f, true)
                   .g;
      }
      ref[std::size_t(y) * d.n + x] = sum * 2 * kPi / rays;
    }
  });
  return ref;
}

struct Row {
  std::string name;
  RenderOptions o;
};

// Signed relative error as a picture: blue below, red above, white at 0, saturating at +-10%.
Status write_error_png(const std::string& path, const Disk& d, const ImageRgb& f) {
  std::vector<unsigned char> px(std::size_t(d.n) * d.n * 3, 40);
  for (int y = 0; y < d.n; ++y)
    for (int x = 0; x < d.n; ++x) {
      unsigned char* p = &px[(std::size_t(y) * d.n + x) * 3];
      if (!d.counted(x, y)) continue;
      const double e = std::clamp((f.at(x, y).g - d.exact(x, y)) / d.exact(x, y) / 0.1, -1.0, 1.0);
      const double w = 1 - std::abs(e);
      p[0] = (unsigned char)(255 * (e > 0 ? 1 : w));
      p[1] = (unsigned char)(255 * w);
      p[2] = (unsigned char)(255 * (e < 0 ? 1 : w));
    }
  return io::write_png8(path, d.n, d.n, px);
}

}  // namespace

static int run(const std::string& program, const std::string& dir) {
  Disk d;
  SceneDesc desc;
  desc.width = desc.height = d.n;
  desc.shapes.resize(1);  // (a braced Shape here trips GCC 12's -Wmaybe-uninitialized)
  desc.shapes[0].geometry = Circle{{d.cx, d.cy}, d.r};
  desc.shapes[0].material = Material{{d.L, d.L, d.L}, 1, {}};
  const Scene scene = *build_scene(desc);
  const std::vector<double> ref = grid_reference(d, scene);

  std::vector<Row> rows;
  auto add = [&](std::string name, auto edit) {
    RenderOptions o;
    edit(o);
    rows.push_back({std::move(name), o});
  };
  for (float t0 : {1.0f, 2.0f, 4.0f, 8.0f}) {
    for (MergeFix fix : {MergeFix::bilinear, MergeFix::none, MergeFix::nearest})
      add("t0 " + std::to_string(int(t0)) + ", fix " + to_string(fix), [&](RenderOptions& o) {
        o.rc.interval = t0;
        o.rc.fix = fix;
      });
  }
  add("t0 4, fix bilinear, preaverage", [](RenderOptions& o) { o.rc.preaverage = true; });
  add("t0 4, fix bilinear, spacing 2", [](RenderOptions& o) { o.rc.probe_spacing = 2; });
  add("t0 4, fix bilinear, 8 directions", [](RenderOptions& o) { o.rc.directions = 8; });
  add("t0 8, fix bilinear, 8 directions",
      [](RenderOptions& o) { o.rc.directions = 8, o.rc.interval = 8; });
  add("t0 8, fix bilinear, branching 2",
      [](RenderOptions& o) { o.rc.branching = 2, o.rc.interval = 8; });
  add("t0 4, fix none, extend 8",
      [](RenderOptions& o) { o.rc.fix = MergeFix::none, o.rc.extend = true; });

  // The reference path tracer: its error falls towards the exact grid's as samples grow.
  for (int spp : {16, 64, 256})
    for (Sampler sampler : {Sampler::random, Sampler::r1})
      add(std::string("pt, ") + to_string(sampler) + ", " + std::to_string(spp) + " spp",
          [&](RenderOptions& o) {
            o.method = Method::pt;
            o.pt.sampler = sampler;
            o.pt.spp = spp;
          });
  for (int spp : {16, 64, 256, 1024})
    add("pt, r1, nee, " + std::to_string(spp) + " spp", [&](RenderOptions& o) {
      o.method = Method::pt;
      o.pt.nee = true;
      o.pt.spp = spp;
    });
  std::printf(
      "| options | mean rel. error vs closed form | max | mean rel. error vs exact grid | max | "
      "time (ms) |\n");
  std::printf("| --- | ---: | ---: | ---: | ---: | ---: |\n");
  for (const Row& row : rows) {
    Expected<RenderResult> r = render(scene, row.o);
    if (!r) {
      std::fprintf(stderr, "%s: %s\n", row.name.c_str(), r.error().message.c_str());
      return 1;
    }
    double mean_a = 0, max_a = 0, mean_g = 0, max_g = 0;
    int na = 0, ng = 0;
    for (int y = 0; y < d.n; ++y)
      for (int x = 0; x < d.n; ++x) {
        if (!d.counted(x, y)) continue;
        const double v = r->fluence.at(x, y).g;
        const double ea = std::abs(v - d.exact(x, y)) / d.exact(x, y);
        mean_a += ea, max_a = std::max(max_a, ea), ++na;
        const double g = ref[std::size_t(y) * d.n + x];
        if (g <= 0) continue;
        const double eg = std::abs(v - g) / g;
        mean_g += eg, max_g = std::max(max_g, eg), ++ng;
      }
    std::printf("| %s | %.2f%% | %.2f%% | %.2f%% | %.2f%% | %.0f |\n", row.name.c_str(),
                100 * mean_a / na, 100 * max_a, 100 * mean_g / ng, 100 * max_g, r->time_ms);
    std::fflush(stdout);
    if (row.name == "t0 4, fix bilinear" || row.name == "t0 4, fix none") {
      const std::string tag = row.name == "t0 4, fix bilinear" ? "bilinear" : "vanilla";
      Status st = write_error_png(dir + "/disk_error_" + tag + ".png", d, r->fluence);
      if (st) st = write_image(dir + "/disk_" + tag + ".png", r->fluence, scene, {-1});
      if (!st) {
        std::fprintf(stderr, "%s: %s\n", program.c_str(), st.error().message.c_str());
        return tool::kCannotWrite;
      }
    }
  }
  return 0;
}

int main(int argc, char** argv) {
  CLI::App app{
      "RC and the path tracer against the closed form of a disk light: a markdown table "
      "on stdout, pictures into the folder (about 35 s)",
      "penumbra_quality"};
  std::string dir = ".";
  app.add_option("folder", dir, "Where the pictures go (made if missing, in a folder that exists)")
      ->capture_default_str();
  if (const std::optional<int> stop = tool::parse(app, argc, argv)) return *stop;
  if (!tool::output_folder(app.get_name(), dir)) return tool::kCannotWrite;
  for (const char* tag : {"bilinear", "vanilla"})
    for (const std::string& f :
         {dir + "/disk_error_" + tag + ".png", dir + "/disk_" + tag + ".png"})
      if (Status st = check_output(f); !st) {
        std::fprintf(stderr, "%s: %s\n", app.get_name().c_str(), st.error().message.c_str());
        return tool::kCannotWrite;
      }
  return run(app.get_name(), dir);
}
