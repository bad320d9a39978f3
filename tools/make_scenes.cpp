// Writes the generated example scenes (lights_*, fog, painted) and their image layers into a
// folder, normally scenes/:  penumbra_make_scenes scenes
//
// The output is the same bytes on every run and machine: fixed seeds, integer hashing instead of
// <random> distributions, and no transcendental functions (whose last bit may vary between
// math libraries), so `git diff` after regenerating shows nothing.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "bench_scenes.hpp"
#include "core/tone_map.hpp"
#include "io/image_io.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/io.hpp"
#include "tool_cli.hpp"

namespace penumbra::flatland {
namespace {

// ---------------------------------------------------------------------------------------------
// Scene files, written by the library's scene_json

struct SceneFile {
  std::string name;  // file name without ".json"
  std::string description;
  SceneDesc desc;  // its `layers` are not written: `files` names them
  LayerFiles files;
};

// A size x size scene file without layers or shapes yet.
SceneFile square_scene(std::string name, int size, Rgb environment, std::string description) {
  SceneFile f;
  f.name = std::move(name);
  f.description = std::move(description);
  f.desc.width = f.desc.height = size;
  f.desc.environment = environment;
  return f;
}

// ---------------------------------------------------------------------------------------------
// Deterministic noise

std::uint32_t hash(std::uint32_t x, std::uint32_t y, std::uint32_t seed) {
  std::uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}

// Uniform in [0, 1) from 24 hash bits.
float hash01(int x, int y, std::uint32_t seed) {
  return float(hash(std::uint32_t(x), std::uint32_t(y), seed) >> 8) * 0x1p-24f;
}

float smoothstep(float e0, float e1, float x) {
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

float lerp(float a, float b, float t) {
  return a + (b - a) * t;
}

// Value noise in [0, 1] with a quintic fade (smooth first and second derivatives).
float value_noise(float x, float y, std::uint32_t seed) {
  const float fx = std::floor(x), fy = std::floor(y);
  const int ix = int(fx), iy = int(fy);
  auto fade = [](float t) { return t * t * t * (t * (t * 6 - 15) + 10); };
  const float u = fade(x - fx), v = fade(y - fy);
  const float a = lerp(hash01(ix, iy, seed), hash01(ix + 1, iy, seed), u);
  const float b = lerp(hash01(ix, iy + 1, seed), hash01(ix + 1, iy + 1, seed), u);
  return lerp(a, b, v);
}

// Fractal sum of `octaves` value noises, each twice the frequency and half the amplitude of the
// previous one, normalised to [0, 1].
float fbm(float x, float y, int octaves, std::uint32_t seed) {
  float sum = 0, amp = 1, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * value_noise(x, y, seed + std::uint32_t(o) * 101u);
    norm += amp;
    amp *= 0.5f;
    x *= 2;
    y *= 2;
  }
  return sum / norm;
}

// ---------------------------------------------------------------------------------------------
// Layer pictures

// A single-channel float plane, row 0 at the top.
struct Plane {
  int width = 0, height = 0;
  std::vector<float> v;
  Plane(int w, int h, float fill = 0) : width(w), height(h), v(std::size_t(w) * h, fill) {}
  float& at(int x, int y) { return v[std::size_t(y) * width + x]; }
};

// Three planes as an 8-bit RGB picture (values in [0, 1], stored as they are).
ImageRgb8 picture(const Plane& r, const Plane& g, const Plane& b) {
  ImageRgb8 p{r.width, r.height, std::vector<unsigned char>(r.v.size() * 3)};
  for (std::size_t i = 0; i < r.v.size(); ++i) {
    p.rgb[3 * i] = to_byte(std::clamp(r.v[i], 0.0f, 1.0f));
    p.rgb[3 * i + 1] = to_byte(std::clamp(g.v[i], 0.0f, 1.0f));
    p.rgb[3 * i + 2] = to_byte(std::clamp(b.v[i], 0.0f, 1.0f));
  }
  return p;
}

// ---------------------------------------------------------------------------------------------
// The lights scenes: seed 001's scene-independence experiment (figure 13: 2, 102 and 1002
// lights take the same time). The layout is bench::lights_scene, so the benchmark and the files
// agree.

SceneFile lights(int count) {
  SceneFile f;
  f.name = "lights_" + std::to_string(count);
  f.description =
      std::to_string(count) +
      " small coloured lights among four fixed occluders (the benchmark's lights_scene, "
      "seed 001's figure 13): radiance cascades trace the same intervals whatever "
      "the number of lights.";
  f.desc = bench::lights_scene(512, count);
  return f;
}

// ---------------------------------------------------------------------------------------------
// Fog: a fog whose density comes from an opacity layer (domain-warped fractal noise, thicker
// near the floor), lit by a warm light through a slatted screen and a cold lamp, with a pillar
// casting a volumetric shadow.

constexpr int kFogSize = 512;

Plane fog_opacity() {
  Plane p(kFogSize, kFogSize);
  for (int y = 0; y < kFogSize; ++y) {
    for (int x = 0; x < kFogSize; ++x) {
      // Domain warping turns round blobs into drifting wisps.
      const float wx = fbm(x / 160.0f, y / 160.0f, 3, 11), wy = fbm(x / 160.0f, y / 160.0f, 3, 29);
      const float n = fbm(x / 110.0f + 1.6f * wx, y / 110.0f + 1.6f * wy, 5, 7);
      const float clumps = smoothstep(0.40f, 0.75f, n);
      const float floor = smoothstep(100.0f, 512.0f, float(y));  // ground fog
      const float density = clumps * (0.5f + 0.5f * floor);      // clear air between wisps
      p.at(x, y) = 0.03f * density;
    }
  }
  return p;
}

// Opacities of a thin fog are a few 8-bit steps; random dithering keeps their average exact
// (light integrates over many cells, so the per-cell noise averages out; banding would not).
Plane dither_to_bytes(const Plane& p, std::uint32_t seed) {
  Plane q = p;
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x) {
      const float v = q.at(x, y) * 255 + hash01(x, y, seed) - 0.5f;
      q.at(x, y) = std::clamp(std::floor(v + 0.5f), 0.0f, 255.0f) / 255;
    }
  return q;
}

Shape disk(float x, float y, float r, Material m) {
  return {Circle{{x, y}, r}, m};
}
Shape box(float x, float y, float w, float h, float angle, Material m) {
  return {Box{{x, y}, {w, h}, angle}, m};
}
Material light(Rgb e) {
  return {e, 1, {}};
}
Material solid(Rgb albedo) {
  return {{}, 1, albedo};
}

SceneFile fog() {
  SceneFile f = square_scene(
      "fog", kFogSize, {0, 0, 0},
      "Volumetric fog of varying density (an opacity layer) lit through a slatted screen and by "
      "a cold lamp; a pillar casts a volumetric shadow. Try --bounces 3.");
  SceneDesc& d = f.desc;
  f.files.opacity = "layers/fog_opacity.png";
  f.files.albedo = "layers/fog_albedo.png";
  // A warm light in the top-left corner behind a diagonal screen of slats: shafts fan out.
  d.shapes.push_back(disk(46, 46, 16, light({16, 10, 5})));
  for (int i = 0; i < 7; ++i)
    d.shapes.push_back(box(24 + 26 * i, 200 - 26 * i, 20, 8, -45, solid({0.5f, 0.5f, 0.5f})));
  // A cold lamp low on the right.
  d.shapes.push_back(disk(440, 420, 8, light({2, 6, 14})));
  // A pillar between both lights.
  d.shapes.push_back(disk(310, 300, 24, solid({0.6f, 0.6f, 0.6f})));
  return f;
}

// ---------------------------------------------------------------------------------------------
// Painted: emission, opacity and albedo layers painted with a soft round brush, as a person
// would in a paint program: thick strokes, blobs and a few strokes of coloured light.

constexpr int kPaintSize = 512;

struct Canvas {
  Plane er{kPaintSize, kPaintSize}, eg{kPaintSize, kPaintSize}, eb{kPaintSize, kPaintSize};
  Plane opacity{kPaintSize, kPaintSize};
  Plane ar{kPaintSize, kPaintSize}, ag{kPaintSize, kPaintSize}, ab{kPaintSize, kPaintSize};
};

// What a brush lays down: emission and albedo in sRGB, as a paint program shows colours.
struct Paint {
  Rgb emission{};
  float opacity = 1;
  Rgb albedo{};
};

struct Pt {
  float x, y;
};

// sqrt is correctly rounded everywhere; std::hypot need not be.
float distance(Pt a, Pt b) {
  return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y));
}

// Catmull-Rom spline through `pts` (ends repeated), sampled finely.
std::vector<Pt> spline(const std::vector<Pt>& pts) {
  std::vector<Pt> out;
  const int n = int(pts.size());
  for (int i = 0; i + 1 < n; ++i) {
    const Pt p0 = pts[std::max(i - 1, 0)], p1 = pts[i], p2 = pts[i + 1],
             p3 = pts[std::min(i + 2, n - 1)];
    for (int k = 0; k < 32; ++k) {
      const float t = float(k) / 32, t2 = t * t, t3 = t2 * t;
      auto cr = [&](float a, float b, float c, float d) {
        return 0.5f * (2 * b + (c - a) * t + (2 * a - 5 * b + 4 * c - d) * t2 +
                       (3 * b - a - 3 * c + d) * t3);
      };
      out.push_back({cr(p0.x, p1.x, p2.x, p3.x), cr(p0.y, p1.y, p2.y, p3.y)});
    }
  }
  out.push_back(pts.back());
  return out;
}

// One stroke: dabs of a soft round brush every fifth of a radius along the spline, the radius
// swelling in the middle and tapering at the ends like pen pressure. The stroke's coverage is
// the maximum of its dabs (as a paint program does within one stroke), then blended over.
void stroke(Canvas& c, const std::vector<Pt>& pts, float radius, float softness, Paint p,
            float taper = 0.6f) {
  Plane cover(kPaintSize, kPaintSize);
  const std::vector<Pt> path = spline(pts);
  float length = 0;
  for (std::size_t i = 1; i < path.size(); ++i) length += distance(path[i], path[i - 1]);
  float along = 0, next = 0;
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (i > 0) along += distance(path[i], path[i - 1]);
    if (along < next && i + 1 < path.size()) continue;
    const float s = length > 0 ? along / length : 0.5f;  // 0..1 along the stroke
    const float pressure = 1 - taper * (2 * s - 1) * (2 * s - 1);
    const float r = radius * pressure;
    next = along + std::max(r * 0.2f, 0.5f);
    const int x0 = std::max(0, int(path[i].x - r - 1)),
              x1 = std::min(kPaintSize - 1, int(path[i].x + r + 1));
    const int y0 = std::max(0, int(path[i].y - r - 1)),
              y1 = std::min(kPaintSize - 1, int(path[i].y + r + 1));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const float d = distance({x + 0.5f, y + 0.5f}, path[i]);
        const float k = 1 - smoothstep(r * (1 - softness), r, d);
        cover.at(x, y) = std::max(cover.at(x, y), k);
      }
  }
  for (int y = 0; y < kPaintSize; ++y)
    for (int x = 0; x < kPaintSize; ++x) {
      const float k = cover.at(x, y);
      if (k <= 0) continue;
      c.er.at(x, y) = lerp(c.er.at(x, y), p.emission.r, k);
      c.eg.at(x, y) = lerp(c.eg.at(x, y), p.emission.g, k);
      c.eb.at(x, y) = lerp(c.eb.at(x, y), p.emission.b, k);
      c.opacity.at(x, y) = lerp(c.opacity.at(x, y), p.opacity, k);
      // Paint is a little uneven: its colour varies slowly over the canvas.
      const float grain = 0.85f + 0.3f * fbm(x / 14.0f, y / 14.0f, 3, 5);
      c.ar.at(x, y) = lerp(c.ar.at(x, y), std::min(p.albedo.r * grain, 1.0f), k);
      c.ag.at(x, y) = lerp(c.ag.at(x, y), std::min(p.albedo.g * grain, 1.0f), k);
      c.ab.at(x, y) = lerp(c.ab.at(x, y), std::min(p.albedo.b * grain, 1.0f), k);
    }
}

// A blob: a short, fat stroke.
void blob(Canvas& c, Pt at, float radius, Paint p) {
  stroke(
      c,
      {{at.x - radius * 0.3f, at.y + radius * 0.1f}, {at.x + radius * 0.3f, at.y - radius * 0.1f}},
      radius, 0.5f, p, 0.25f);
}

Paint wall(Rgb albedo) {
  return {{}, 1, albedo};
}
Paint glow(Rgb emission) {
  return {emission, 1, {}};
}

Canvas paint() {
  Canvas c;
  // Opaque walls cast the shadows: an ochre ground line, a rose swirl, a pale arch.
  stroke(c, {{-20, 488}, {90, 466}, {200, 482}, {320, 458}, {430, 474}, {540, 450}}, 14, 0.4f,
         wall({0.85f, 0.62f, 0.35f}), 0.2f);
  stroke(c, {{150, 130}, {210, 95}, {262, 128}, {250, 186}, {196, 196}, {178, 160}}, 7, 0.45f,
         wall({0.9f, 0.5f, 0.6f}));
  stroke(c, {{40, 330}, {70, 250}, {130, 220}, {180, 262}, {196, 336}}, 6, 0.5f,
         wall({0.92f, 0.9f, 0.82f}));
  // Translucent paint lets light in and scatters its colour (with bounces): teal clouds and a
  // violet glaze.
  const Paint teal{{}, 0.06f, {0.45f, 0.95f, 0.85f}};
  blob(c, {380, 250}, 42, teal);
  blob(c, {418, 304}, 26, teal);
  stroke(c, {{280, 60}, {360, 110}, {470, 90}}, 30, 0.9f, {{}, 0.04f, {0.9f, 0.75f, 1.0f}}, 0.3f);
  // Light: an orange stroke, a cyan squiggle, magenta dots, a yellow blob.
  stroke(c, {{60, 400}, {120, 360}, {190, 392}, {250, 372}}, 5, 0.5f, glow({1.0f, 0.55f, 0.12f}));
  stroke(c, {{300, 170}, {320, 150}, {340, 175}, {360, 150}, {380, 172}, {400, 148}}, 3.5f, 0.5f,
         glow({0.2f, 0.85f, 1.0f}));
  for (Pt at : {Pt{90, 120}, Pt{110, 150}, Pt{76, 168}}) blob(c, at, 7, glow({1.0f, 0.3f, 0.8f}));
  blob(c, {470, 370}, 11, glow({1.0f, 0.92f, 0.45f}));
  return c;
}

SceneFile painted() {
  SceneFile f = square_scene(
      "painted", kPaintSize, {0.004f, 0.004f, 0.008f},
      "Emission, opacity and albedo PNG layers painted with a soft brush: strokes of coloured "
      "light among painted walls and a translucent glaze. Try --bounces 3.");
  f.files = {"layers/painted_emission.png", "layers/painted_opacity.png",
             "layers/painted_albedo.png", 8};
  return f;
}

// ---------------------------------------------------------------------------------------------

int run(const std::filesystem::path& dir) {
  std::vector<std::pair<std::string, std::string>> texts;
  std::vector<std::pair<std::string, ImageRgb8>> pictures;
  auto scene = [&](const SceneFile& f) {
    texts.emplace_back((dir / (f.name + ".json")).string(),
                       scene_json(f.desc, f.files, f.description));
  };
  auto layer = [&](const std::string& name, const Plane& r, const Plane& g, const Plane& b) {
    pictures.emplace_back((dir / name).string(), picture(r, g, b));
  };

  for (int n : {2, 102, 1002}) scene(lights(n));

  const SceneFile fog_scene = fog();
  const Plane opacity = dither_to_bytes(fog_opacity(), 3);
  layer(fog_scene.files.opacity, opacity, opacity, opacity);
  // A bright, slightly blue fog (sRGB values, as in a paint program; linear about 0.8-0.9).
  const Plane ar(kFogSize, kFogSize, 0.906f), ag(kFogSize, kFogSize, 0.925f),
      ab(kFogSize, kFogSize, 0.955f);
  layer(fog_scene.files.albedo, ar, ag, ab);
  scene(fog_scene);

  const SceneFile painted_scene = painted();
  const Canvas c = paint();
  layer(painted_scene.files.emission, c.er, c.eg, c.eb);
  layer(painted_scene.files.opacity, c.opacity, c.opacity, c.opacity);
  layer(painted_scene.files.albedo, c.ar, c.ag, c.ab);
  scene(painted_scene);

  std::error_code ec;
  std::filesystem::create_directory(dir / "layers", ec);
  // Pictures, then scene files, each set all or nothing: a scene never names a missing layer.
  Status s = write_pictures(pictures);
  if (s) s = io::write_text_files(texts);
  if (!s) {
    std::fprintf(stderr, "penumbra_make_scenes: %s\n", s.error().message.c_str());
    return 1;
  }
  for (const auto& [path, picture] : pictures) std::printf("wrote %s\n", path.c_str());
  for (const auto& [path, text] : texts) std::printf("wrote %s\n", path.c_str());
  return 0;
}

}  // namespace
}  // namespace penumbra::flatland

int main(int argc, char** argv) {
  CLI::App app{"Writes the generated example scenes and their image layers (scenes/README.md)",
               "penumbra_make_scenes"};
  std::string dir;
  app.add_option("folder", dir,
                 "Where they go, e.g. scenes (made if missing, in a folder that exists)")
      ->required();
  if (const std::optional<int> stop = penumbra::tool::parse(app, argc, argv)) return *stop;
  if (!penumbra::tool::output_folder(app.get_name(), dir)) return penumbra::tool::kCannotWrite;
  return penumbra::flatland::run(dir);
}
