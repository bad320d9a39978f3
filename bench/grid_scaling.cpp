// The world-space probe grid's time and memory per cascade against the grid's size, the table
// docs/PERFORMANCE.md shows: the scene voxelised with its longest side in 32, 64, 128 and 256
// voxels, the cascades solved (one bounce) walking every voxel, leaping over empty space (the
// default), and leaping with interval extension; per cascade its probes, directions, bytes
// against the seed's M_0 / 2^i, and milliseconds; per size the totals and their ratio to the
// size below (a doubling of the grid). Each solve runs `--runs` times; the median is reported.
//
//   penumbra_grid_scaling [--scene scenes/3d/cornell.json] [--sizes 32,64,128,256] [--runs 3]
//                         [--extend-length 8]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "core/median.hpp"
#include "core/timer.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "spaceland/grid/grid.hpp"
#include "spaceland/sky.hpp"
#include "tool_cli.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::spaceland;

struct Timed {
  double total = 0;
  std::vector<double> cascade;  // per cascade, medians
  std::vector<grid::CascadePlan> plan;
};

Timed time_solve(const grid::Voxels& v, const Background& bg, const GridOptions& o, int runs) {
  std::vector<double> totals;
  std::vector<std::vector<double>> per;
  Timed t;
  for (int r = 0; r < runs; ++r) {
    Stopwatch watch;
    Expected<grid::RadianceField> sol = grid::solve(v, bg, o, std::uint64_t(64) << 30);
    if (!sol) {
      std::fprintf(stderr, "%s\n", sol.error().message.c_str());
      std::exit(1);
    }
    totals.push_back(watch.ms());
    per.resize(sol->cascade_ms().size());
    for (std::size_t i = 0; i < per.size(); ++i) per[i].push_back(sol->cascade_ms()[i]);
    t.plan = sol->cascades();
  }
  t.total = median(totals);
  for (const std::vector<double>& c : per) t.cascade.push_back(median(c));
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The probe grid's time and memory per cascade against the grid's size",
               "penumbra_grid_scaling"};
  std::string path = std::string(PENUMBRA_SCENES_DIR) + "/3d/cornell.json";
  std::vector<int> sizes = {32, 64, 128, 256};
  int runs = 3;
  float extend_length = 8;
  app.add_option("--scene", path, "A 3D scene")->capture_default_str();
  app.add_option("--sizes", sizes, "Voxels along the scene's longest side")->delimiter(',');
  app.add_option("--runs", runs, "Solves per configuration (median)")->check(CLI::Range(1, 100));
  app.add_option("--extend-length", extend_length, "Traced length with extension, voxels")
      ->check(CLI::Range(1.0f, 1e6f));
  if (const std::optional<int> stop = penumbra::tool::parse(app, argc, argv)) return *stop;

  Expected<Scene> scene = load_scene(path);
  if (!scene) {
    std::fprintf(stderr, "%s\n", scene.error().message.c_str());
    return 1;
  }
  const Background bg(*scene);
  const Bounds b = grid::grid_bounds(*scene);
  const Vec3 e = b.hi - b.lo;
  const double longest = std::max({double(e.x), double(e.y), double(e.z)});
  std::printf(
      "Scene %s, one bounce, defaults (s0 2 voxels, Q0 16, t0 4 probe spacings); "
      "median of %d solves.\n\n",
      path.c_str(), runs);
  std::printf(
      "| longest side | voxels | voxelise | walk | leap (default) | leap + extension "
      "(%g voxels) | leap vs walk | default / size below |\n",
      double(extend_length));
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- |\n");
  double previous = 0;
  std::vector<std::string> details;
  for (int n : sizes) {
    const float size = float(longest / n);
    Stopwatch watch;
    Expected<grid::Voxels> voxels = grid::voxelise(*scene, size, std::uint64_t(64) << 30);
    if (!voxels) {
      std::fprintf(stderr, "%s\n", voxels.error().message.c_str());
      return 1;
    }
    const double voxelise_ms = watch.ms();
    grid::Voxels walk = *voxels;
    walk.skip.clear();
    GridOptions o;
    const Timed plain = time_solve(walk, bg, o, runs);
    const Timed leap = time_solve(*voxels, bg, o, runs);
    o.extend_length = extend_length;
    const Timed extended = time_solve(*voxels, bg, o, runs);
    char row[512];
    std::snprintf(
        row, sizeof row,
        "| %d | %d x %d x %d | %.0f ms | %.0f ms | %.0f ms | %.0f ms | %.2fx | %s |\n", n,
        voxels->nx, voxels->ny, voxels->nz, voxelise_ms, plain.total, leap.total, extended.total,
        plain.total / leap.total,
        previous > 0 ? (std::to_string(leap.total / previous).substr(0, 4) + "x").c_str() : "");
    std::fputs(row, stdout);
    previous = leap.total;
    // Per cascade: the seed's law M_i = M_0 / 2^i against the bytes planned.
    std::string d = "\nLongest side " + std::to_string(n) + " voxels:\n\n" +
                    "| cascade | probes | directions | MiB | M_0 / 2^i | walk | leap | leap + "
                    "extension |\n| --- | --- | --- | --- | --- | --- | --- | --- |\n";
    const double m0 = double(leap.plan[0].bytes()) / double(1 << 20);
    for (std::size_t i = 0; i < leap.plan.size(); ++i) {
      const grid::CascadePlan& c = leap.plan[i];
      char line[256];
      std::snprintf(line, sizeof line,
                    "| %zu | %d x %d x %d | %d | %.2f | %.2f | %.1f ms | %.1f ms | %.1f ms |\n", i,
                    c.nx, c.ny, c.nz, c.side * c.side, double(c.bytes()) / double(1 << 20),
                    m0 / double(1 << i), plain.cascade[i], leap.cascade[i], extended.cascade[i]);
      d += line;
    }
    details.push_back(d);
  }
  for (const std::string& d : details) std::fputs(d.c_str(), stdout);
  return 0;
}
