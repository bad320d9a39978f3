// Holographic radiance cascades and RC on small lights beside occluders (issue 36): a family of
// scenes, each two disk lights of radius 4-8 cells either side of a thin wall at 256^2 or 512^2,
// against the exact fluence of the same cell grid (exact DDA rays, densely over the angles the
// lights subtend). Writes a markdown table on stdout (docs/QUALITY.md).
//
//   build/bin/penumbra_quality_walls > table.md
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/math.hpp"
#include "core/parallel.hpp"
#include "flatland/trace.hpp"
#include "penumbra/penumbra.hpp"
#include "tool_cli.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::flatland;

struct Light {
  float x, y, r;
};

struct Case {
  SceneDesc desc;
  Light lights[2];
  int stride;  // the cells counted: every stride-th along x and y
};

// Scene `seed` of the family: a wall 1.5-3 cells thick and 0.25-0.5 of the grid long, turned up
// to 30 degrees from the vertical, and a disk light of radius 4-8 on each side of it, 6-40
// cells from it, of a random colour.
Case make_case(unsigned seed) {
  std::mt19937 rng(seed);
  auto u = [&rng] { return double(rng() >> 8) * 0x1p-24; };  // the same on every library
  Case c;
  const int n = seed % 2 ? 256 : 512;
  c.stride = n / 128;
  SceneDesc& d = c.desc;
  d.width = d.height = n;
  const double cx = n * (0.5 + (u() - 0.5) / 8), cy = n * (0.5 + (u() - 0.5) / 8);
  const double thick = 1.5 + 1.5 * u(), length = n * (0.25 + 0.25 * u());
  const double angle = (u() - 0.5) * 60;  // degrees from the vertical
  d.shapes.push_back(
      {Box{{float(cx), float(cy)}, {float(thick), float(length)}, float(angle)}, Material{}});
  const double a = angle * kPi / 180, ax = -std::sin(a), ay = std::cos(a);  // along the wall
  for (int side = 0; side < 2; ++side) {
    const double r = 4 + 4 * u(), off = thick / 2 + r + 6 + 34 * u();
    const double along = (u() - 0.5) * length;
    const double s = side ? 1 : -1;
    const double x = cx + along * ax + s * off * ay, y = cy + along * ay - s * off * ax;
    const float L[3] = {float(1 + 3 * u()), float(1 + 3 * u()), float(1 + 3 * u())};
    c.lights[side] = {float(x), float(y), float(r)};
    d.shapes.push_back(
        {Circle{{float(x), float(y)}, float(r)}, Material{{L[0], L[1], L[2]}, 1, {}}});
  }
  return c;
}

// The exact fluence (green) at cell (x, y)'s centre: DDA rays over the angles each light
// subtends (its rasterised disk is at most r + 1 from its centre), 2048 per merged interval, the
// whole circle (16384 rays) where the cell is that close to a light.
double exact(const Medium& m, const Case& c, int x, int y) {
  const double px = x + 0.5, py = y + 0.5;
  std::vector<std::pair<double, double>> spans;
  for (const Light& l : c.lights) {
    const double dx = l.x - px, dy = l.y - py, dist = std::hypot(dx, dy);
    if (dist <= l.r + 1.5) {
      spans = {{0, 2 * kPi}};
      break;
    }
    const double mid = std::atan2(dy, dx), half = std::asin((l.r + 1.5) / dist);
    double a = mid - half, b = mid + half;
    if (a < 0) a += 2 * kPi, b += 2 * kPi;
    if (b > 2 * kPi) {
      spans.push_back({a, 2 * kPi});
      spans.push_back({0, b - 2 * kPi});
    } else {
      spans.push_back({a, b});
    }
  }
  std::sort(spans.begin(), spans.end());
  std::vector<std::pair<double, double>> merged;
  for (const auto& s : spans)
    if (!merged.empty() && s.first <= merged.back().second)
      merged.back().second = std::max(merged.back().second, s.second);
    else
      merged.push_back(s);
  double sum = 0;
  for (const auto& [a, b] : merged) {
    const int rays = b - a >= 2 * kPi ? 16384 : 2048;
    double part = 0;
    for (int k = 0; k < rays; ++k) {
      const double t = a + (b - a) * (k + 0.5) / rays;
      part += trace_interval(m, float(px), float(py), float(std::cos(t)), float(std::sin(t)), 0,
                             1e5f, true)
                  .g;
    }
    sum += part * (b - a) / rays;
  }
  return sum;
}

struct Config {
  std::string name;
  RenderOptions o;
};

int run(int scenes, bool rings, int pt_spp) {
  std::vector<Config> configs;
  auto add = [&](std::string name, auto edit) {
    RenderOptions o;
    edit(o);
    configs.push_back({std::move(name), o});
  };
  add("hrc (defaults)", [](RenderOptions& o) { o.method = Method::hrc; });
  add("hrc --wall-fan 0", [](RenderOptions& o) { o.method = Method::hrc, o.hrc.wall_fan = 0; });
  add("hrc --fan-share 0.0625",
      [](RenderOptions& o) { o.method = Method::hrc, o.hrc.fan_share = 1.0f / 16; });
  add("rc (defaults)", [](RenderOptions& o) { o.method = Method::rc; });
  add("hrc --near-fan 0", [](RenderOptions& o) { o.method = Method::hrc, o.hrc.near_fan = 0; });
  add("hrc --wall-fan 4 --near-fan 8",
      [](RenderOptions& o) { o.method = Method::hrc, o.hrc.wall_fan = 4, o.hrc.near_fan = 8; });
  if (pt_spp > 0)
    add("pt --nee " + std::to_string(pt_spp) + " spp",
        [&](RenderOptions& o) { o.method = Method::pt, o.pt.nee = true, o.pt.spp = pt_spp; });
  std::vector<std::vector<double>> errors(configs.size());
  std::printf("| scene | grid | radii | wall (thick x long, angle) |");
  for (const Config& c : configs) std::printf(rings ? " %s | rings |" : " %s |", c.name.c_str());
  std::printf("\n| ---: | ---: | ---: | ---: |");
  for (std::size_t i = 0; i < configs.size(); ++i)
    std::printf(rings ? " ---: | ---: |" : " ---: |");
  std::printf("\n");
  for (int seed = 1; seed <= scenes; ++seed) {
    const Case c = make_case(unsigned(seed));
    Expected<Scene> scene = build_scene(c.desc);
    if (!scene) {
      std::fprintf(stderr, "scene %d: %s\n", seed, scene.error().message.c_str());
      return 1;
    }
    Medium m = make_medium(*scene);
    build_distance_field(m);
    const int n = scene->width, s = c.stride;
    std::vector<std::pair<int, int>> counted;
    for (int y = s / 2; y < n; y += s)
      for (int x = s / 2; x < n; x += s)
        if (scene->opacity[scene->index(x, y)] == 0.0f) counted.push_back({x, y});
    std::vector<double> ref(counted.size());
    parallel_for(int(counted.size()),
                 [&](int i) { ref[i] = exact(m, c, counted[i].first, counted[i].second); });
    double mean = 0;
    for (double r : ref) mean += r / double(ref.size());
    const Box& wall = std::get<Box>(c.desc.shapes[0].geometry);
    std::printf("| %d | %d^2 | %.1f, %.1f | %.1f x %.0f, %.0f deg |", seed, n, c.lights[0].r,
                c.lights[1].r, wall.size[0], wall.size[1], wall.angle);
    for (std::size_t k = 0; k < configs.size(); ++k) {
      Expected<RenderResult> r = render(*scene, configs[k].o);
      if (!r) {
        std::fprintf(stderr, "%s: %s\n", configs[k].name.c_str(), r.error().message.c_str());
        return 1;
      }
      double e2 = 0;
      for (std::size_t i = 0; i < counted.size(); ++i) {
        const double e = r->fluence.at(counted[i].first, counted[i].second).g - ref[i];
        e2 += e * e / double(counted.size());
      }
      errors[k].push_back(std::sqrt(e2) / mean);
      std::printf(" %.2f%% |", 100 * errors[k].back());
      if (rings) {  // where the error lies: within 3 cells of a light's rim, 3-10, 10-30, farther
        double ring[4] = {0, 0, 0, 0};
        for (std::size_t i = 0; i < counted.size(); ++i) {
          double from = 1e9;
          for (const Light& l : c.lights)
            from = std::min(
                from,
                std::hypot(counted[i].first + 0.5 - l.x, counted[i].second + 0.5 - l.y) - l.r);
          const double e = r->fluence.at(counted[i].first, counted[i].second).g - ref[i];
          ring[from < 3 ? 0 : from < 10 ? 1 : from < 30 ? 2 : 3] += e * e / double(counted.size());
        }
        std::printf(" %.2f / %.2f / %.2f / %.2f |", 100 * std::sqrt(ring[0]) / mean,
                    100 * std::sqrt(ring[1]) / mean, 100 * std::sqrt(ring[2]) / mean,
                    100 * std::sqrt(ring[3]) / mean);
      }
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  std::printf("| median | | | |");
  for (std::vector<double>& e : errors) {
    std::sort(e.begin(), e.end());
    const std::size_t h = e.size() / 2;
    std::printf(rings ? " %.2f%% | |" : " %.2f%% |",
                100 * (e.size() % 2 ? e[h] : (e[h - 1] + e[h]) / 2));
  }
  std::printf("\n| worst | | | |");
  for (const std::vector<double>& e : errors)
    std::printf(rings ? " %.2f%% | |" : " %.2f%% |", 100 * e.back());
  std::printf("\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "HRC and RC against the exact fluence of two small disk lights either side of a thin "
      "wall, 8 scenes at 256^2 and 512^2: a markdown table of relative RMSE on stdout (about a "
      "minute on 2 cores)",
      "penumbra_quality_walls"};
  int scenes = 8, pt_spp = 0;
  bool rings = false;
  app.add_option("--scenes", scenes, "How many scenes of the family")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_flag("--rings", rings,
               "Also split each error by the distance to the nearer light's rim: within 3 cells, "
               "3-10, 10-30, farther (each the share of the whole relative RMSE: their squares "
               "add up to it)");
  app.add_option("--pt", pt_spp, "Also the path tracer with NEE at this many samples per cell")
      ->check(CLI::Range(1, 1 << 20));
  if (const std::optional<int> stop = penumbra::tool::parse(app, argc, argv)) return *stop;
  return run(scenes, rings, pt_spp);
}
