// The 3D path tracer against closed forms (docs/QUALITY.md, "3D path tracer against closed
// forms"): each scene is built here, rendered at 1 to 1024 samples per pixel and measured at every
// pixel whose first hit the closed form covers. Writes a markdown table on stdout and, into the
// folder given, quality3d.csv, quality3d.md, the convergence plot (quality3d.svg, .png) and one
// picture per scene.
//
//   build/bin/penumbra_quality3d docs/quality/3d > table.md
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/text.hpp"
#include "core/math.hpp"
#include "io/image_io.hpp"
#include "penumbra/io.hpp"
#include "penumbra/spaceland/io.hpp"
#include "penumbra/spaceland/render.hpp"
#include "tool_cli.hpp"

namespace {

using namespace penumbra;
using namespace penumbra::spaceland;

using penumbra::tool::kCannotWrite;

// A scene, how many bounces it is rendered with, and its closed form: the exact radiance towards
// the camera given the pixel's first hit (world position, object index), or nothing where the
// closed form does not hold (the light itself, a penumbra).
struct Case {
  std::string name, setup, closed_form;
  Scene scene;
  int bounces = 1;
  std::function<std::optional<Rgb>(Vec3 hit, int object)> exact;
  bool picture = true;  // one picture per scene, not per bounce count
};

// Appends a material and the object line that names it; returns the material's index.
std::uint32_t add(Scene& s, const char* what, Rgb albedo, Rgb emission = {}) {
  Material m;
  m.albedo = albedo;
  m.emission = emission;
  m.name = what;
  s.materials.push_back(m);
  s.objects.push_back(std::string("objects[") + char('0' + s.objects.size()) + "] (" + what + ")");
  return std::uint32_t(s.materials.size() - 1);
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

Scene looking(Vec3 from, Vec3 at, int w, int h, float fov) {
  Scene s;
  s.camera.position = from;
  s.camera.look_at = at;
  s.camera.width = w;
  s.camera.height = h;
  s.camera.fov_y = fov;
  return s;
}

Rgb scale(Rgb c, double k) {
  return {float(c.r * k), float(c.g * k), float(c.b * k)};
}

double distance2(Vec3 a, Vec3 b) {
  return dot(a - b, a - b);
}

// An enclosure whose inside emits Le and reflects a: Le (1 + a + ... + a^N) everywhere. With fog
// that reflects a and emits sigma Le per unit length, the answer stays the same. The box's
// triangles are sampled by area (real noise); a sphere seen from inside makes every sample exact.
enum class Shell { box, box_fog, sphere };
Case enclosure(int bounces, Shell shell) {
  const Rgb le{1.0f, 0.5f, 0.25f};
  const float a = 0.6f;
  const std::string n = std::to_string(bounces) + (bounces > 1 ? " bounces" : " bounce");
  Case c{shell == Shell::sphere    ? "sphere enclosure, " + n
         : shell == Shell::box_fog ? "enclosure + fog, " + n
                                   : "enclosure, " + n,
         shell == Shell::sphere
             ? "the inside of a sphere of radius 1, albedo 0.6, emitting Le = (1, 0.5, 0.25); "
               "camera inside, 48x36, fov 90"
             : "the inside of the box [-1, 1] x [-1.25, 1.25] x [-1.5, 1.5] (12 triangles), albedo "
               "0.6, emitting Le = (1, 0.5, 0.25); camera inside, 48x36, fov 90",
         "Le (1 + a + ... + a^N)",
         looking({0.2f, -0.1f, 0.3f}, {0.6f, 0.3f, -1}, 48, 36, 90),
         bounces,
         {}};
  const std::uint32_t wall = add(c.scene, shell == Shell::sphere ? "sphere" : "box", {a, a, a}, le);
  if (shell == Shell::sphere) {
    c.scene.spheres.push_back({{0, 0, 0}, 1, wall, 0});
  } else {
    // Each face: the corner (u, v) = (+-1, +-1) of the side s = +-1 along the axis.
    TriangleMesh m;
    const float h[3] = {1, 1.25f, 1.5f};
    for (int axis = 0; axis < 3; ++axis)
      for (float side : {-1.0f, 1.0f}) {
        const auto b = std::uint32_t(m.positions.size());
        for (auto [u, v] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
          float p[3];
          p[axis] = side * h[axis];
          p[(axis + 1) % 3] = u * h[(axis + 1) % 3];
          p[(axis + 2) % 3] = v * h[(axis + 2) % 3];
          m.positions.push_back({p[0], p[1], p[2]});
        }
        m.triangles.push_back({b, b + 1, b + 2});
        m.triangles.push_back({b, b + 2, b + 3});
      }
    m.materials.assign(m.triangles.size(), wall);
    m.object = 0;
    c.scene.meshes.push_back(m);
  }
  if (shell == Shell::box_fog) {
    c.setup +=
        "; a fog box of half sizes 0.5 x 0.6 x 0.7 inside, extinction (0.5, 1, 2), albedo 0.6, "
        "emitting extinction x Le";
    Medium m;
    m.half_size = {0.5f, 0.6f, 0.7f};
    m.extinction = {0.5f, 1, 2};
    m.albedo = {a, a, a};
    m.emission = {0.5f * le.r, 1 * le.g, 2 * le.b};
    c.scene.media.push_back(m);
  }
  double sum = 0, p = 1;
  for (int k = 0; k <= bounces; ++k, p *= a) sum += p;
  c.exact = [le, sum](Vec3, int) -> std::optional<Rgb> { return scale(le, sum); };
  c.picture = bounces == 4;
  return c;
}

// A disk of radius 1000 (the plane y = 0, albedo a) seen from above at 96x72.
Scene plane(float albedo, float radius = 1000) {
  Scene s = looking({0, 3, 4}, {0, 0, 0}, 96, 72, 50);
  Disk d;
  d.radius = radius;
  d.material = add(s, "plane", {albedo, albedo, albedo});
  d.object = 0;
  s.disks.push_back(d);
  return s;
}

Case sphere_light(float radius = 1000) {
  Case c{radius < 1000 ? "sphere light, plane radius " + fmt("%g", radius) : "sphere light",
         "a sphere of radius 0.4 at (-0.4, 1.6, 0.2) emitting Le = (5, 4, 3) over the plane y = 0 "
         "(a disk of radius " +
             fmt("%g", radius) + ") of albedo 0.7; black sky; 96x72",
         "a Le (r / d)^2 cos(theta), d the distance to the centre",
         plane(0.7f, radius),
         1,
         {}};
  const Vec3 o{-0.4f, 1.6f, 0.2f};
  const float r = 0.4f;
  c.scene.spheres.push_back({o, r, add(c.scene, "light", {0, 0, 0}, {5, 4, 3}), 1});
  c.exact = [o, r](Vec3 p, int object) -> std::optional<Rgb> {
    if (object != 0) return std::nullopt;
    const double d2 = distance2(o, p), cos_t = (o.y - p.y) / std::sqrt(d2);
    return scale({5, 4, 3}, 0.7 * r * r / d2 * cos_t);
  };
  return c;
}

// The plane's radius sets the scene's scale, and with it the offset of rays leaving the plane
// (RayScene::spawn): 1000 as in the other scenes, or 20 to show what that offset costs.
Case sky(float radius) {
  Case c{
      radius < 1000 ? "sky, black sphere, plane radius " + fmt("%g", radius) : "sky, black sphere",
      "a uniform sky L = (1.5, 1, 0.5) over the plane y = 0 (a disk of radius " +
          fmt("%g", radius) +
          ") of albedo 0.6; a black sphere of radius 0.6 at (0.5, 1.2, -0.3); 96x72",
      "a L (1 - (r / d)^2 cos(theta))",
      plane(0.6f, radius),
      1,
      {}};
  c.picture = radius >= 1000;
  const Rgb l{1.5f, 1, 0.5f};
  c.scene.sky = {l, l, l};
  const Vec3 o{0.5f, 1.2f, -0.3f};
  const float r = 0.6f;
  c.scene.spheres.push_back({o, r, add(c.scene, "blocker", {0, 0, 0}), 1});
  c.exact = [l, o, r](Vec3 p, int object) -> std::optional<Rgb> {
    if (object != 0) return std::nullopt;
    const double d2 = distance2(o, p), cos_t = (o.y - p.y) / std::sqrt(d2);
    return scale(l, 0.6 * (1 - r * r / d2 * cos_t));
  };
  return c;
}

Case sun() {
  Case c{"sun, hard shadow",
         "the sun towards (0.4, 1, -0.3), irradiance E = (2.5, 2, 1.5), angular radius 0.27 deg, "
         "over the plane y = 0 (a disk of radius 1000) of albedo 0.8; a black disk of radius 0.6 "
         "at height 1 casts the "
         "shadow; 96x72",
         "a E cos(theta) / pi in the light, 0 in the umbra (the penumbra left out)",
         plane(0.8f),
         1,
         {}};
  Scene& s = c.scene;
  s.has_sun = true;
  s.sun.direction = normalize(Vec3{0.4f, 1, -0.3f});
  s.sun.irradiance = {2.5f, 2, 1.5f};
  Disk d;
  d.center = {0, 1, 0};
  d.radius = 0.6f;
  d.material = add(s, "blocker", {0, 0, 0});
  d.object = 1;
  s.disks.push_back(d);
  const Sun sun = s.sun;
  c.exact = [sun, d](Vec3 p, int object) -> std::optional<Rgb> {
    if (object != 0) return std::nullopt;
    // Where the ray towards the sun's centre crosses the disk's plane, and how far the penumbra
    // reaches from the shadow's edge there (twice its half-width, plus float slack).
    const double t = (d.center.y - p.y) / sun.direction.y;
    const double rho = std::hypot(p.x + t * sun.direction.x, p.z + t * sun.direction.z);
    const double margin = 0.01 + 2 * t * std::tan(sun.angular_radius * kPi / 180);
    if (std::abs(rho - d.radius) < margin) return std::nullopt;
    if (rho < d.radius) return Rgb{};
    return scale(sun.irradiance, 0.8 * sun.direction.y / kPi);
  };
  return c;
}

// One pixel row after another looking down -z at a wall (z = -3) through a slab of fog (z from
// -1 to -2): every ray spends a third of its length in the fog.
Case slab(bool emitting) {
  Case c{emitting ? "fog, emission" : "fog, Beer-Lambert",
         emitting ? "a slab of fog 1 deep (z from -1 to -2), extinction sigma = (0.5, 1, 2), "
                    "albedo 0, emitting e = (1, 2, 3) per unit length, before a black wall; "
                    "48x36, fov 40"
                  : "a slab of fog 1 deep (z from -1 to -2), extinction sigma = (0.5, 1, 2), "
                    "albedo 0, before a wall emitting Lw = 2; 48x36, fov 40",
         emitting ? "e (1 - exp(-sigma l)) / sigma, l = |hit| / 3 the length in the fog"
                  : "Lw exp(-sigma l), l = |hit| / 3 the length in the fog",
         looking({0, 0, 0}, {0, 0, -1}, 48, 36, 40),
         1,
         {}};
  const Rgb sigma{0.5f, 1, 2}, e{1, 2, 3}, wall = emitting ? Rgb{} : Rgb{2, 2, 2};
  Disk w;
  w.center = {0, 0, -3};
  w.normal = {0, 0, 1};
  w.radius = 10;
  w.material = add(c.scene, "wall", {0, 0, 0}, wall);
  w.object = 0;
  c.scene.disks.push_back(w);
  Medium m;
  m.center = {0, 0, -1.5f};
  m.half_size = {5, 5, 0.5f};
  m.extinction = sigma;
  m.emission = emitting ? e : Rgb{};
  c.scene.media.push_back(m);
  c.exact = [=](Vec3 p, int) -> std::optional<Rgb> {
    const double l = length(p) / 3;
    auto one = [&](double s, double em, double lw) {
      const double t = std::exp(-s * l);
      return float(lw * t + em * (1 - t) / s);
    };
    return Rgb{one(sigma.r, m.emission.r, wall.r), one(sigma.g, m.emission.g, wall.g),
               one(sigma.b, m.emission.b, wall.b)};
  };
  return c;
}

struct Metrics {
  int pixels = 0;
  double rel_rmse = 0, rel_bias = 0, max_rel = 0, time_ms = 0;
};

struct Row {
  const Case* c;
  int spp;
  Metrics m;
};

Expected<ImageRgb> render_image(const Case& c, int spp, Aov aov, double* time_ms = nullptr) {
  RenderOptions o;
  o.pt.spp = spp;
  o.bounces = c.bounces;
  o.aov = aov;
  Expected<RenderResult> r = render(c.scene, o);
  if (!r) return r.error();
  if (time_ms) *time_ms = r->time_ms;
  return std::move(r->radiance);
}

// Over the 3 channels of every covered pixel: RMSE and bias over the mean of the closed form;
// the largest error over the closed form's value (over its mean where the value is 0: the umbra).
Metrics measure(const ImageRgb& got, const std::vector<std::optional<Rgb>>& want) {
  double se = 0, sum_e = 0, sum_w = 0, worst = 0, worst_at_zero = 0;
  Metrics m;
  for (std::size_t k = 0; k < want.size(); ++k) {
    if (!want[k]) continue;
    ++m.pixels;
    const float* g = got.data() + 3 * k;
    const float w[3] = {want[k]->r, want[k]->g, want[k]->b};
    for (int i = 0; i < 3; ++i) {
      const double e = double(g[i]) - w[i];
      se += e * e, sum_e += e, sum_w += w[i];
      if (w[i] > 0)
        worst = std::max(worst, std::abs(e) / w[i]);
      else
        worst_at_zero = std::max(worst_at_zero, std::abs(e));
    }
  }
  const double n = 3.0 * m.pixels, mean = sum_w / n;
  m.rel_rmse = std::sqrt(se / n) / mean;
  m.rel_bias = sum_e / n / mean;
  m.max_rel = std::max(worst, worst_at_zero / mean);
  return m;
}

// Each pixel's closed form, evaluated at its first hit (or nothing where it does not hold).
Expected<std::vector<std::optional<Rgb>>> closed_form(const Case& c) {
  Expected<ImageRgb> pos = render_image(c, 1, Aov::position), obj = render_image(c, 1, Aov::object);
  if (!pos || !obj) return (pos ? obj : pos).error();
  std::vector<std::optional<Rgb>> want(std::size_t(pos->width()) * pos->height());
  for (std::size_t k = 0; k < want.size(); ++k) {
    const float* p = pos->data() + 3 * k;
    want[k] = c.exact({p[0], p[1], p[2]}, int(obj->data()[3 * k]));
  }
  return want;
}

// A configuration of a method's table: what it changes from the defaults, given the options
// the defaults' render used (which run first: derived lengths are known then).
struct TableRun {
  std::string label;
  std::function<void(RenderOptions&, const RenderOptions& defaults)> set;
};

// One scene's table for `method` at the scene's bounce count: a row per run; `column` names the
// derived length shown (t0 or the voxel) and reads it from the options used. `csv` gets a line
// per run.
Expected<std::string> method_table(const Case& c, Method method, const std::string& title,
                                   const std::vector<TableRun>& runs, const char* column,
                                   float (*length)(const RenderOptions&), std::ostringstream& csv) {
  Expected<std::vector<std::optional<Rgb>>> want = closed_form(c);
  if (!want) return want.error();
  std::ostringstream md;
  md << "**" << c.name << "** (" << title << ", " << c.bounces
     << (c.bounces > 1 ? " bounces" : " bounce") << ").\n\n"
     << "| configuration | " << column
     << " | rel. RMSE | rel. bias | max rel. error | time (ms) |\n"
     << "| --- | ---: | ---: | ---: | ---: | ---: |\n";
  RenderOptions defaults;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    RenderOptions o;
    o.method = method;
    o.bounces = c.bounces;
    if (k > 0) runs[k].set(o, defaults);
    Expected<RenderResult> r = render(c.scene, o);
    if (!r) return Error{c.name + ", " + runs[k].label + ": " + r.error().message};
    if (k == 0) defaults = r->options;
    const Metrics m = measure(r->radiance, *want);
    const RenderOptions& used = r->options;
    md << "| " << runs[k].label << " | " << fmt("%.3g", length(used)) << " | "
       << fmt("%.3g%%", 100 * m.rel_rmse) << " | " << fmt("%+.2g%%", 100 * m.rel_bias) << " | "
       << fmt("%.3g%%", 100 * m.max_rel) << " | " << fmt("%.0f", r->time_ms) << " |\n";
    csv << '"' << c.name << "\",\"" << runs[k].label << "\"," << fmt("%.6g", length(used)) << ','
        << fmt("%.6g", m.rel_rmse) << ',' << fmt("%.6g", m.rel_bias) << ','
        << fmt("%.6g", m.max_rel) << ',' << fmt("%.1f", r->time_ms) << '\n';
  }
  md << "\n";
  return md.str();
}

// SPWI (one bounce) on the closed-form scenes it can render: each merge, then the settings
// docs/QUALITY.md studies.
Expected<std::string> spwi_table(const Case& c, std::ostringstream& csv) {
  using O = RenderOptions;
  std::vector<TableRun> runs = {{"defaults (bilinear3d)", {}}};
  for (SpwiMerge m : {SpwiMerge::bilinear, SpwiMerge::bilateral, SpwiMerge::fix, SpwiMerge::minmax})
    runs.push_back(
        {std::string("--merge ") + to_string(m), [m](O& o, const O&) { o.spwi.merge = m; }});
  for (double k : {0.25, 0.5, 2.0})
    runs.push_back({"t0 " + fmt("%g", k) + "x",
                    [k](O& o, const O& d) { o.spwi.interval = float(k * d.spwi.interval); }});
  runs.push_back({"--probe-spacing 2", [](O& o, const O&) { o.spwi.probe_spacing = 2; }});
  runs.push_back({"--directions 256", [](O& o, const O&) { o.spwi.directions = 256; }});
  runs.push_back({"--preaverage", [](O& o, const O&) { o.spwi.preaverage = true; }});
  runs.push_back({"--branching 16", [](O& o, const O&) { o.spwi.branching = 16; }});
  runs.push_back({"--disjoint", [](O& o, const O&) { o.spwi.overlap = false; }});
  runs.push_back({"--sun cascades", [](O& o, const O&) { o.spwi.sun = SpwiSun::cascades; }});
  return method_table(
      c, Method::spwi, "SPWI", runs, "t0", [](const O& o) { return o.spwi.interval; }, csv);
}

// The probe grid on the closed-form scenes: its defaults, the voxel at half and twice its size,
// s0 and Q0 each way, the bilinear fix and interval extension.
Expected<std::string> grid_table(const Case& c, std::ostringstream& csv) {
  using O = RenderOptions;
  const std::vector<TableRun> runs = {
      {"defaults", {}},
      {"voxel 0.5x", [](O& o, const O& d) { o.grid.voxel = 0.5f * d.grid.voxel; }},
      {"voxel 2x", [](O& o, const O& d) { o.grid.voxel = 2 * d.grid.voxel; }},
      {"--probe-spacing 1", [](O& o, const O&) { o.grid.probe_spacing = 1; }},
      {"--probe-spacing 4", [](O& o, const O&) { o.grid.probe_spacing = 4; }},
      {"--directions 64", [](O& o, const O&) { o.grid.directions = 64; }},
      {"--fix bilinear", [](O& o, const O&) { o.grid.fix = true; }},
      {"--extend", [](O& o, const O&) { o.grid.extend_length = 8; }}};
  return method_table(
      c, Method::grid, "the probe grid", runs, "voxel", [](const O& o) { return o.grid.voxel; },
      csv);
}

// Exponent k of error ~ spp^-k, least squares in log-log over the rows with an error above 0.
double order(const std::vector<Row>& rows) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (const Row& r : rows) {
    if (!(r.m.rel_rmse > 0)) continue;
    const double x = std::log(r.spp), y = std::log(r.m.rel_rmse);
    sx += x, sy += y, sxx += x * x, sxy += x * y, ++n;
  }
  return n < 2 ? NAN : -(n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// The fitted order, or "exact" where every error is float rounding (no slope to fit).
std::string order_text(const std::vector<Row>& rows) {
  for (const Row& r : rows)
    if (r.m.rel_rmse > 1e-6) return fmt("%.2f", order(rows));
  return "exact (float rounding)";
}

// The convergence plot: relative RMSE against samples per pixel, log-log (x in powers of 4, y in
// decades), one line per scene and the 1/sqrt(N) and 1/N slopes dashed from the largest 1-spp
// error. The same layout gives the SVG and the PNG (docs/quality's style).
struct Plot {
  static constexpr double H = 480, top = 40, bottom = 50, frame = 480;
  double left = 80, right = 250;    // as wide as the longest tick label and legend name need
  double x1 = 10, y0 = -2, y1 = 0;  // log4 of the largest spp; decades of the error
  struct Series {
    std::string name;
    analysis::Colour colour;
    bool dashed;
    std::vector<std::pair<double, double>> points;  // pixel positions
  };
  std::vector<Series> series;
  double px(double spp) const { return left + std::log(spp) / std::log(4.0) / x1 * frame; }
  double py(double e) const { return top + (y1 - std::log10(e)) / (y1 - y0) * (H - top - bottom); }
};

Plot layout(const std::vector<std::vector<Row>>& curves) {
  Plot p;
  double emin = INFINITY, emax = 0, first = 0;
  int max_spp = 1;
  for (const auto& rows : curves)
    for (const Row& r : rows) {
      max_spp = std::max(max_spp, r.spp);
      if (r.spp == 1) first = std::max(first, r.m.rel_rmse);
      if (r.m.rel_rmse > 0)
        emin = std::min(emin, r.m.rel_rmse), emax = std::max(emax, r.m.rel_rmse);
    }
  p.x1 = std::max(1.0, std::ceil(std::log(max_spp) / std::log(4.0) - 1e-9));
  p.y0 = std::floor(std::log10(emin)), p.y1 = std::max(p.y0 + 1, std::ceil(std::log10(emax)));
  for (double d = p.y0; d <= p.y1; ++d)
    p.left = std::max(p.left, 30.0 + analysis::text_width(fmt("%g%%", 100 * std::pow(10, d)), 2));
  for (const auto& rows : curves)
    p.right = std::max(p.right, 44.0 + analysis::text_width(rows.front().c->name, 2));
  static const analysis::Colour palette[] = {{31, 119, 180},  {255, 127, 14},  {44, 160, 44},
                                             {214, 39, 40},   {148, 103, 189}, {140, 86, 75},
                                             {227, 119, 194}, {188, 189, 34},  {23, 190, 207},
                                             {0, 0, 128},     {174, 199, 232}};
  int k = 0;
  for (const auto& rows : curves) {
    Plot::Series s{rows.front().c->name, palette[k++ % 12], false, {}};
    for (const Row& r : rows)
      if (r.m.rel_rmse > 0) s.points.push_back({p.px(r.spp), p.py(r.m.rel_rmse)});
    p.series.push_back(s);
  }
  for (double slope : {0.5, 1.0}) {
    Plot::Series s{slope == 0.5 ? "1/sqrt(N)" : "1/N", {90, 90, 90}, true, {}};
    for (int spp = 1; spp <= max_spp; spp *= 4)
      if (double e = first / std::pow(spp, slope); e >= std::pow(10, p.y0))
        s.points.push_back({p.px(spp), p.py(e)});
    p.series.push_back(s);
  }
  return p;
}

const char* kXLabel = "samples per pixel";
const char* kYLabel = "relative RMSE against the closed form";

std::string hex(analysis::Colour c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
  return buf;
}

std::string to_svg(const Plot& p, const std::string& title) {
  std::ostringstream s;
  s << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << p.left + p.frame + p.right
    << "\" height=\"" << p.H << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"" << p.left
    << "\" y=\"24\" font-size=\"15\">" << title << "</text>\n";
  auto line = [&](double ax, double ay, double bx, double by, const char* stroke) {
    s << "<line x1=\"" << ax << "\" y1=\"" << ay << "\" x2=\"" << bx << "\" y2=\"" << by
      << "\" stroke=\"" << stroke << "\"/>\n";
  };
  for (int d = 0; d <= p.x1; ++d) {
    const double x = p.px(std::pow(4, d));
    line(x, p.top, x, p.H - p.bottom, "#ddd");
    s << "<text x=\"" << x << "\" y=\"" << p.H - p.bottom + 16 << "\" text-anchor=\"middle\">"
      << int(std::pow(4, d)) << "</text>\n";
  }
  for (double d = p.y0; d <= p.y1; ++d) {
    const double y = p.py(std::pow(10, d));
    line(p.left, y, p.left + p.frame, y, "#ddd");
    s << "<text x=\"" << p.left - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">"
      << fmt("%g%%", 100 * std::pow(10, d)) << "</text>\n";
  }
  s << "<rect x=\"" << p.left << "\" y=\"" << p.top << "\" width=\"" << p.frame << "\" height=\""
    << p.H - p.top - p.bottom << "\" fill=\"none\" stroke=\"#333\"/>\n<text x=\""
    << p.left + p.frame / 2 << "\" y=\"" << p.H - 12 << "\" text-anchor=\"middle\">" << kXLabel
    << "</text>\n<text transform=\"translate(18," << (p.top + p.H - p.bottom) / 2
    << ") rotate(-90)\" text-anchor=\"middle\">" << kYLabel << "</text>\n";
  double legend_y = p.top + 10;
  for (const Plot::Series& c : p.series) {
    s << "<polyline fill=\"none\" stroke=\"" << hex(c.colour) << "\" stroke-width=\"2\""
      << (c.dashed ? " stroke-dasharray=\"6,4\"" : "") << " points=\"";
    for (auto [x, y] : c.points) s << x << "," << y << " ";
    s << "\"/>\n";
    if (!c.dashed)
      for (auto [x, y] : c.points)
        s << "<circle cx=\"" << x << "\" cy=\"" << y << "\" r=\"3\" fill=\"" << hex(c.colour)
          << "\"/>\n";
    s << "<rect x=\"" << p.left + p.frame + 14 << "\" y=\"" << legend_y - 8
      << "\" width=\"14\" height=\"" << (c.dashed ? 2 : 8) << "\" fill=\"" << hex(c.colour)
      << "\"/><text x=\"" << p.left + p.frame + 34 << "\" y=\"" << legend_y << "\">" << c.name
      << "</text>\n";
    legend_y += 18;
  }
  s << "</svg>\n";
  return s.str();
}

ImageRgb8 to_png(const Plot& p, const std::string& title) {
  const int w = int(p.left + p.frame + p.right);
  ImageRgb8 img{w, int(p.H), std::vector<unsigned char>(std::size_t(w * p.H * 3), 255)};
  const analysis::Colour grid{221, 221, 221}, ink{40, 40, 40};
  // Dashed lines draw every other 8-pixel stretch.
  auto line = [&](double ax, double ay, double bx, double by, analysis::Colour c, int thick,
                  bool dashed = false) {
    const int n = int(std::max(std::abs(bx - ax), std::abs(by - ay))) + 1;
    for (int i = 0; i <= n; ++i)
      if (!dashed || (i / 8) % 2 == 0)
        analysis::fill_rect(img, int(ax + (bx - ax) * i / n) - thick / 2,
                            int(ay + (by - ay) * i / n) - thick / 2, thick, thick, c);
  };
  const int sc = 2, half = analysis::line_height(sc) / 2;
  const double fr = p.left + p.frame, fb = p.H - p.bottom;
  analysis::draw_text(img, int(p.left), 10, title, ink, sc);
  for (int d = 0; d <= p.x1; ++d) {
    const double x = p.px(std::pow(4, d));
    const std::string label = std::to_string(int(std::pow(4, d)));
    line(x, p.top, x, fb, grid, 1);
    analysis::draw_text(img, int(x) - analysis::text_width(label, sc) / 2, int(fb) + 6, label, ink,
                        sc);
  }
  for (double d = p.y0; d <= p.y1; ++d) {
    const double y = p.py(std::pow(10, d));
    const std::string label = fmt("%g%%", 100 * std::pow(10, d));
    line(p.left, y, fr, y, grid, 1);
    analysis::draw_text(img, int(p.left) - 6 - analysis::text_width(label, sc), int(y) - half,
                        label, ink, sc);
  }
  for (auto [ax, ay, bx, by] : {std::array{p.left, p.top, fr, p.top},
                                {p.left, fb, fr, fb},
                                {p.left, p.top, p.left, fb},
                                {fr, p.top, fr, fb}})
    line(ax, ay, bx, by, ink, 1);
  const std::string xlabel = std::string(kXLabel) + "; y: relative RMSE";
  analysis::draw_text(img, int(p.left + p.frame / 2) - analysis::text_width(xlabel, sc) / 2,
                      int(p.H) - 22, xlabel, ink, sc);
  int legend_y = int(p.top) + 4;
  for (const Plot::Series& c : p.series) {
    for (std::size_t i = 0; i + 1 < c.points.size(); ++i)
      line(c.points[i].first, c.points[i].second, c.points[i + 1].first, c.points[i + 1].second,
           c.colour, 2, c.dashed);
    if (!c.dashed)
      for (auto [x, y] : c.points) analysis::fill_rect(img, int(x) - 3, int(y) - 3, 7, 7, c.colour);
    analysis::fill_rect(img, int(fr) + 12, legend_y + (c.dashed ? 5 : 2), 14, c.dashed ? 2 : 8,
                        c.colour);
    analysis::draw_text(img, int(fr) + 32, legend_y, c.name, ink, sc);
    legend_y += analysis::line_height(sc) + 4;
  }
  return img;
}

// The display picture, enlarged by whole pixels to at least 256 wide so it can be seen.
ImageRgb8 enlarged(const ImageRgb& image) {
  const ImageRgb8 small = display_picture(image, Aov::radiance);
  const int z = std::max(1, 256 / small.width);
  ImageRgb8 big{small.width * z, small.height * z, {}};
  big.rgb.resize(std::size_t(big.width) * big.height * 3);
  for (int y = 0; y < big.height; ++y)
    for (int x = 0; x < big.width; ++x)
      for (int i = 0; i < 3; ++i)
        big.rgb[(std::size_t(y) * big.width + x) * 3 + i] =
            small.rgb[(std::size_t(y / z) * small.width + x / z) * 3 + i];
  return big;
}

std::string slug(const std::string& name) {
  std::string s;
  for (char ch : name)
    if (std::isalnum(static_cast<unsigned char>(ch)))
      s += char(std::tolower(static_cast<unsigned char>(ch)));
    else if (!s.empty() && s.back() != '_')
      s += '_';
  while (!s.empty() && s.back() == '_') s.pop_back();
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The 3D path tracer against closed forms: errors at 1 to 1024 samples per pixel",
               "penumbra_quality3d"};
  std::string dir;
  bool quick = false;
  app.add_option("folder", dir, "Where the CSV, the plot and the pictures go (must exist)")
      ->required();
  app.add_flag("--quick", quick, "Up to 64 samples per pixel instead of 1024");
  bool spwi_only = false, grid_only = false;
  app.add_flag("--spwi-only", spwi_only,
               "Only SPWI's table (spwi3d.md, spwi3d.csv), not the path tracer's curves");
  app.add_flag("--grid-only", grid_only,
               "Only the probe grid's table (grid3d.md, grid3d.csv), not the path tracer's");
  if (const std::optional<int> stop = penumbra::tool::parse(app, argc, argv)) return *stop;
  for (const char* f : {"/quality3d.csv", "/quality3d.png"})
    if (Status st = check_output(dir + f); !st) {
      std::fprintf(stderr, "%s\n", st.error().message.c_str());
      return kCannotWrite;
    }

  // A method's tables on `cases`, to stdout as they come and to <dir>/<name>.md and .csv.
  auto tables = [&](const std::vector<Case>& cases, const std::string& name, const char* column,
                    const char* intro, auto&& table) -> int {
    std::ostringstream md, csv;
    csv << "scene,configuration," << column
        << ",relative_rmse,relative_bias,max_relative_error,time_ms\n";
    md << intro << " against the closed forms: relative RMSE over the pixels the closed form "
       << "covers, defaults unless the row says otherwise.\n\n";
    for (const Case& c : cases) {
      Expected<std::string> t = table(c, csv);
      if (!t) {
        std::fprintf(stderr, "%s\n", t.error().message.c_str());
        return 1;
      }
      std::fputs(t->c_str(), stdout);
      std::fflush(stdout);
      md << *t;
    }
    if (Status st = io::write_text_files(
            {{dir + "/" + name + ".csv", csv.str()}, {dir + "/" + name + ".md", md.str()}});
        !st) {
      std::fprintf(stderr, "%s\n", st.error().message.c_str());
      return kCannotWrite;
    }
    return 0;
  };
  // The probe grid: the enclosures at 1 to 4 bounces (with fog, and a sphere's), the sphere
  // light and the sky over planes small enough for its voxels, the sun, the fog slabs.
  if (grid_only) {
    std::vector<Case> cases;
    for (int n = 1; n <= 4; ++n) cases.push_back(enclosure(n, Shell::box));
    cases.push_back(enclosure(4, Shell::box_fog));
    cases.push_back(enclosure(4, Shell::sphere));
    cases.push_back(sphere_light(4));
    cases.push_back(sky(4));
    cases.push_back(sun());
    cases.push_back(slab(false));
    cases.push_back(slab(true));
    return tables(cases, "grid3d", "voxel", "The probe grid", grid_table);
  }
  // SPWI on the one-bounce scenes without fog.
  if (int code = tables(
          {enclosure(1, Shell::box), enclosure(1, Shell::sphere), sphere_light(), sky(1000), sun()},
          "spwi3d", "t0", "SPWI", spwi_table);
      code != 0 || spwi_only)
    return code;

  std::vector<Case> cases;
  for (int n = 1; n <= 4; ++n) cases.push_back(enclosure(n, Shell::box));
  cases.push_back(enclosure(4, Shell::box_fog));
  cases.push_back(enclosure(4, Shell::sphere));
  cases.push_back(sphere_light());
  cases.push_back(sky(1000));
  cases.push_back(sky(20));
  cases.push_back(sun());
  cases.push_back(slab(false));
  cases.push_back(slab(true));
  std::vector<int> spps = {1, 4, 16, 64};
  if (!quick) spps.insert(spps.end(), {256, 1024});

  std::vector<std::vector<Row>> curves;
  std::vector<std::pair<std::string, ImageRgb8>> pictures;
  std::ostringstream md, csv;
  std::string table;  // stdout again, as quality3d.md
  csv << "scene,bounces,spp,pixels,relative_rmse,relative_bias,max_relative_error,time_ms\n";
  for (const Case& c : cases) {
    // The first hits: where each pixel's closed form is evaluated.
    Expected<std::vector<std::optional<Rgb>>> closed = closed_form(c);
    if (!closed) {
      std::fprintf(stderr, "%s: %s\n", c.name.c_str(), closed.error().message.c_str());
      return 1;
    }
    const std::vector<std::optional<Rgb>>& want = *closed;
    md << "**" << c.name << "**: " << c.setup << ". Closed form: `" << c.closed_form << "`.\n\n"
       << "| spp | pixels | rel. RMSE | rel. bias | max rel. error | time (ms) |\n"
       << "| ---: | ---: | ---: | ---: | ---: | ---: |\n";
    std::vector<Row> rows;
    for (int spp : spps) {
      double ms = 0;
      Expected<ImageRgb> img = render_image(c, spp, Aov::radiance, &ms);
      if (!img) {
        std::fprintf(stderr, "%s: %s\n", c.name.c_str(), img.error().message.c_str());
        return 1;
      }
      Row r{&c, spp, measure(*img, want)};
      r.m.time_ms = ms;
      rows.push_back(r);
      md << "| " << spp << " | " << r.m.pixels << " | " << fmt("%.3g%%", 100 * r.m.rel_rmse)
         << " | " << fmt("%+.2g%%", 100 * r.m.rel_bias) << " | " << fmt("%.3g%%", 100 * r.m.max_rel)
         << " | " << fmt("%.0f", ms) << " |\n";
      csv << '"' << c.name << "\"," << c.bounces << ',' << spp << ',' << r.m.pixels << ','
          << fmt("%.6g", r.m.rel_rmse) << ',' << fmt("%.6g", r.m.rel_bias) << ','
          << fmt("%.6g", r.m.max_rel) << ',' << fmt("%.1f", ms) << '\n';
      if (spp == spps.back() && c.picture)
        pictures.push_back({dir + "/" + slug(c.name) + ".png", enlarged(*img)});
    }
    md << "\nFitted order k (error ~ spp^-k): " << order_text(rows) << ".\n\n";
    std::fputs(md.str().c_str(), stdout);  // as it goes: the full run takes minutes
    std::fflush(stdout);
    curves.push_back(rows);
    table += md.str();
    md.str("");
  }
  md << "| scene | fitted order k (error ~ spp^-k) | rel. RMSE at " << spps.back() << " spp |\n"
     << "| --- | ---: | ---: |\n";
  for (const auto& rows : curves)
    md << "| " << rows.front().c->name << " | " << order_text(rows) << " | "
       << fmt("%.3g%%", 100 * rows.back().m.rel_rmse) << " |\n";
  std::fputs(md.str().c_str(), stdout);
  table += md.str();

  const Plot plot = layout(curves);
  const std::string title = "3D path tracer against closed forms";
  pictures.push_back({dir + "/quality3d.png", to_png(plot, title)});
  if (Status st = io::write_text_files({{dir + "/quality3d.csv", csv.str()},
                                        {dir + "/quality3d.svg", to_svg(plot, title)},
                                        {dir + "/quality3d.md", table}});
      !st) {
    std::fprintf(stderr, "%s\n", st.error().message.c_str());
    return kCannotWrite;
  }
  if (Status st = write_pictures(pictures); !st) {
    std::fprintf(stderr, "%s\n", st.error().message.c_str());
    return kCannotWrite;
  }
  return 0;
}
