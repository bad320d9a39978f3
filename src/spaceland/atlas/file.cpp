#include "spaceland/atlas/file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/fnv.hpp"
#include "io/image_io.hpp"
#include "spaceland/sky.hpp"

namespace penumbra::spaceland::atlas {
namespace {

constexpr const char* kWorld = "3d surface atlas";  // the "penumbra" attribute
// 2: radiance.K in each chart's direction frame (1: the world's), and the chart list gives it.
constexpr int kVersion = 2;
constexpr float kHalfMax = 65504;  // the largest finite 16-bit float

const char* kind_name(ChartKind k) {
  return k == ChartKind::disk ? "disk" : k == ChartKind::sphere ? "sphere" : "mesh";
}

std::string hex(std::uint64_t v) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(v));
  return text;
}

// The baked light's layers, each three channels ("irradiance.front.R", ...), and where they lie in
// Baked, in the same order.
constexpr const char* kLayers[] = {"irradiance.front", "irradiance.back", "sun.front", "sun.back"};
constexpr std::vector<Rgb> Baked::*kLayerOf[] = {&Baked::front, &Baked::back, &Baked::sun_front,
                                                 &Baked::sun_back};

std::string channel(const char* layer, int c) {
  return std::string(layer) + "." + "RGB"[c];
}

float& part(Rgb& v, int c) {
  return c == 0 ? v.r : c == 1 ? v.g : v.b;
}
float part(const Rgb& v, int c) {
  return c == 0 ? v.r : c == 1 ? v.g : v.b;
}

Error damaged(const std::string& path, const std::string& what) {
  return Error{path + ": " + what};
}

}  // namespace

std::uint64_t scene_hash(const Scene& s, bool light) {
  Fnv1a f;
  if (light) hash_light(f, s);
  f.value(s.materials.size());
  for (const Material& m : s.materials) {
    f.value(m.albedo);
    f.value(m.emission);
    f.value(m.metallic);
    f.value(m.roughness);
    for (const TextureRef* t :
         {&m.albedo_texture, &m.emission_texture, &m.metallic_roughness_texture}) {
      f.value(t->index);
      f.value(t->uv_set);
      f.value(t->transform);
    }
  }
  f.value(s.textures.size());
  for (const Texture& t : s.textures) {
    f.value(t.width);
    f.value(t.height);
    f.array(t.rgb);
    f.value(t.wrap_s);
    f.value(t.wrap_t);
    f.value(t.nearest);
  }
  f.value(s.meshes.size());
  for (const TriangleMesh& m : s.meshes) {
    f.array(m.positions);
    f.array(m.normals);
    f.array(m.uvs);
    f.array(m.lightmap_uvs);
    f.array(m.triangles);
    f.array(m.materials);
  }
  f.value(s.spheres.size());
  for (const Sphere& sp : s.spheres) {
    f.value(sp.center);
    f.value(sp.radius);
    f.value(sp.material);
  }
  f.value(s.disks.size());
  for (const Disk& d : s.disks) {
    f.value(d.center);
    f.value(d.normal);
    f.value(d.radius);
    f.value(d.material);
  }
  f.value(s.media.size());
  return f.h;
}

Status write_atlas(const std::string& path, const Baked& b, const Record& r) {
  const Atlas& a = b.atlas;
  io::ExrChannels img;
  img.width = a.width;
  img.height = a.height;
  const std::size_t n = std::size_t(a.width) * std::size_t(a.height);
  nlohmann::json record = {{"texel_size", r.texel_size},
                           {"gutter", r.gutter},
                           {"refine", r.refine},
                           {"max_angle", r.max_angle},
                           {"directions", r.directions},
                           {"interval", r.interval},
                           {"cascades", r.cascades},
                           {"bounces", r.bounces},
                           {"light_exponent", r.light_exponent}};
  nlohmann::json charts = nlohmann::json::array();
  for (const Chart& c : a.charts) {
    const DirectionFrame f = direction_frame(c);
    charts.push_back({{"kind", kind_name(c.kind)},
                      {"shape", c.shape},
                      {"object", c.object},
                      {"x", c.x},
                      {"y", c.y},
                      {"width", c.width},
                      {"height", c.height},
                      {"lightmap", c.from_lightmap},
                      {"frame", {f.x.x, f.x.y, f.x.z, f.y.x, f.y.y, f.y.z, f.z.x, f.z.y, f.z.z}}});
  }
  img.attributes = {{"penumbra", kWorld},
                    {"penumbra.version", std::to_string(kVersion)},
                    {"penumbra.scene_hash", hex(r.scene_hash)},
                    {"penumbra.record", record.dump()},
                    {"penumbra.charts", charts.dump()}};
  if (b.side0 > 0)
    img.attributes.push_back(
        {"penumbra.radiance",
         "radiance.K.{R,G,B}: the radiance arriving from direction K = v * " +
             std::to_string(b.side0) + " + u, the centre of cell (u, v) of the " +
             std::to_string(b.side0) + "x" + std::to_string(b.side0) +
             " equal-area octahedral map of the sphere in the texel's chart's direction frame "
             "(penumbra.charts[c].frame: the map's x, y and z axes in the world), sun "
             "excluded"});

  {
    io::ExrChannel& c = img.channels.emplace_back();
    c.name = "chart";
    c.values.resize(n);
    for (std::size_t k = 0; k < n; ++k) c.values[k] = float(b.texels[k].chart);
  }
  for (int l = 0; l < 4; ++l)
    for (int c = 0; c < 3; ++c) {
      io::ExrChannel& ch = img.channels.emplace_back();
      ch.name = channel(kLayers[l], c);
      ch.values.resize(n);
      for (std::size_t k = 0; k < n; ++k) ch.values[k] = part((b.*kLayerOf[l])[k], c);
    }
  if (b.side0 > 0) {
    const std::size_t nd = std::size_t(b.side0) * std::size_t(b.side0);
    bool half = true;
    for (const Rgb& v : b.radiance)
      half = half && v.r <= kHalfMax && v.g <= kHalfMax && v.b <= kHalfMax;
    for (std::size_t d = 0; d < nd; ++d)
      for (int c = 0; c < 3; ++c) {
        io::ExrChannel& ch = img.channels.emplace_back();
        ch.name = "radiance." + std::to_string(d) + "." + "RGB"[c];
        ch.half = half;
        ch.values.resize(n);
        for (std::size_t k = 0; k < n; ++k) ch.values[k] = part(b.radiance[k * nd + d], c);
      }
  }
  Expected<io::StagedFile> staged = io::stage_exr_channels(path, img);
  if (!staged) return staged.error();
  return io::publish(*staged);
}

Expected<Baked> read_atlas(const std::string& path, const Scene& scene, std::uint64_t max_bytes,
                           Record& r, bool radiance, int bounces) {
  nlohmann::json charts;
  int side0 = 0;
  // The header first, before any pixel is decoded: what the file is, for which scene and bounces.
  auto check_header = [&](const io::ExrChannels& img) -> Status {
    const std::string* world = img.attribute("penumbra");
    if (!world || *world != kWorld)
      return damaged(path, "not a Penumbra surface atlas (its header's `penumbra` attribute is " +
                               (world ? "'" + *world + "'" : std::string("missing")) +
                               "); make one with `penumbra bake`");
    const std::string* version = img.attribute("penumbra.version");
    if (!version || *version != std::to_string(kVersion))
      return damaged(path, "an atlas of version " + (version ? *version : std::string("?")) +
                               ", this build reads version " + std::to_string(kVersion) +
                               "; bake it again");
    const std::string* rec = img.attribute("penumbra.record");
    const std::string* chart_list = img.attribute("penumbra.charts");
    if (!rec || !chart_list) return damaged(path, "the atlas's header lacks its record or charts");
    try {
      const nlohmann::json j = nlohmann::json::parse(*rec);
      r.texel_size = j.at("texel_size").get<float>();
      r.gutter = j.at("gutter").get<int>();
      r.refine = j.value("refine", 0);
      r.max_angle = j.at("max_angle").get<float>();
      r.directions = j.at("directions").get<int>();
      r.interval = j.at("interval").get<float>();
      r.cascades = j.at("cascades").get<int>();
      r.bounces = j.at("bounces").get<int>();
      r.light_exponent = j.at("light_exponent").get<int>();
      charts = nlohmann::json::parse(*chart_list);
      if (!charts.is_array()) throw std::runtime_error("the chart list is no array");
      for (const nlohmann::json& c : charts)
        if (!c.is_object() || !c.at("kind").is_string())
          throw std::runtime_error("a chart is no object with a kind");
    } catch (const std::exception& e) {
      return damaged(path, std::string("the atlas's header is damaged: ") + e.what());
    }
    side0 = side_of(r.directions);
    if (side0 == 0 || !(r.texel_size > 0) || !std::isfinite(r.texel_size) || r.bounces < 1 ||
        r.bounces > 64 || r.refine < 0 || r.refine > 10 || r.light_exponent < 0 ||
        r.light_exponent > 512)
      return damaged(path, "the atlas's record is damaged: " + *rec);
    const std::string* hash = img.attribute("penumbra.scene_hash");
    const std::uint64_t ours = scene_hash(scene);
    if (!hash || *hash != hex(ours))
      return damaged(path, "baked for another scene (its scene hash " +
                               (hash ? *hash : std::string("is missing")) + ", " + scene.source +
                               "'s " + hex(ours) +
                               ": the geometry, materials, sky or sun differ); bake one for it: "
                               "penumbra bake " +
                               scene.source + " -o ATLAS.exr --bounces " +
                               std::to_string(r.bounces) + " --directions " +
                               std::to_string(r.directions));
    r.scene_hash = ours;
    if (bounces > 0 && r.bounces != bounces)
      return damaged(path, "baked with " + std::to_string(r.bounces) + " bounce(s), asked for " +
                               std::to_string(bounces) + ": pass --bounces " +
                               std::to_string(r.bounces) + " or bake it again");
    return {};
  };
  // Half the limit for the decoded channels: beside them the rebuilt charts, the texels and their
  // light (about as much again; with the radiance, its per-texel copy as much as its channels).
  Expected<io::ExrChannels> file = io::read_exr_channels(
      path, max_bytes / 2,
      [&](const std::string& name) { return radiance || !name.starts_with("radiance."); },
      check_header);
  if (!file) return file.error();
  const io::ExrChannels& img = *file;

  Options ao;
  ao.texel_size = r.texel_size;
  ao.gutter = r.gutter;
  ao.refine = r.refine;
  ao.max_angle = r.max_angle;
  // The atlas has the file's size: one that would not fit it is refused before it is built (a
  // damaged texel size would otherwise grow millions of texels).
  ao.max_side = std::max(img.width, img.height);
  Expected<Atlas> made = make_atlas(scene, ao);
  if (!made) return damaged(path, "its charts cannot be rebuilt: " + made.error().message);
  Baked out;
  out.atlas = std::move(*made);
  const Atlas& a = out.atlas;
  bool same = a.width == img.width && a.height == img.height && charts.size() == a.charts.size();
  try {
    for (std::size_t c = 0; same && c < a.charts.size(); ++c) {
      const Chart& ch = a.charts[c];
      const nlohmann::json& f = charts[c];
      same = f.value("kind", "") == kind_name(ch.kind) && f.value("shape", -1) == int(ch.shape) &&
             f.value("x", -1) == ch.x && f.value("y", -1) == ch.y &&
             f.value("width", -1) == ch.width && f.value("height", -1) == ch.height;
    }
  } catch (const std::exception&) {
    same = false;  // a field of another type
  }
  if (!same)
    return damaged(path, "its charts (" + std::to_string(charts.size()) + ", " +
                             std::to_string(img.width) + "x" + std::to_string(img.height) +
                             " texels) are not the ones this build makes for the scene (" +
                             std::to_string(a.charts.size()) + ", " + std::to_string(a.width) +
                             "x" + std::to_string(a.height) + "); bake it again");
  out.texels = rasterise(scene, a);
  const io::ExrChannel* ch = img.channel("chart");
  if (!ch) return damaged(path, "the atlas has no channel 'chart'");
  for (std::size_t k = 0; k < ch->values.size(); ++k)
    if (ch->values[k] != float(out.texels[k].chart))
      return damaged(path, "texel (" + std::to_string(k % std::size_t(a.width)) + ", " +
                               std::to_string(k / std::size_t(a.width)) + ") lies on chart " +
                               std::to_string(ch->values[k]) + " in the file but on chart " +
                               std::to_string(out.texels[k].chart) +
                               " as this build rasterises the scene; bake it again");

  const std::size_t n = std::size_t(a.width) * std::size_t(a.height);
  // A value that cannot be light (negative, not finite) is damage, named where it lies.
  auto take = [&](const std::string& name, std::vector<Rgb>& into, int c) -> Status {
    const io::ExrChannel* ch = img.channel(name);
    if (!ch) return damaged(path, "the atlas has no channel '" + name + "'");
    into.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      const float v = ch->values[k];
      if (!(v >= 0) || !std::isfinite(v))
        return damaged(path, "channel '" + name + "' holds " + std::to_string(v) + " at texel (" +
                                 std::to_string(k % std::size_t(a.width)) + ", " +
                                 std::to_string(k / std::size_t(a.width)) +
                                 "): a damaged atlas; bake it again");
      part(into[k], c) = v;
    }
    return {};
  };
  for (int l = 0; l < 4; ++l)
    for (int c = 0; c < 3; ++c)
      if (Status s = take(channel(kLayers[l], c), out.*kLayerOf[l], c); !s) return s.error();
  // The directional data, where the file has it (one side0^2 map per texel).
  std::size_t radiance_channels = 0;
  for (const io::ExrChannel& c : img.channels) radiance_channels += c.name.starts_with("radiance.");
  if (radiance_channels > 0) {
    const std::size_t nd = std::size_t(side0) * std::size_t(side0);
    if (radiance_channels != 3 * nd)
      return damaged(path, "the atlas has " + std::to_string(radiance_channels) +
                               " radiance channels, expected " + std::to_string(3 * nd) +
                               " for Q0 " + std::to_string(r.directions));
    out.side0 = side0;
    out.radiance.resize(n * nd);
    std::vector<Rgb> one;
    for (std::size_t d = 0; d < nd; ++d)
      for (int c = 0; c < 3; ++c) {
        if (Status s = take("radiance." + std::to_string(d) + "." + "RGB"[c], one, c); !s)
          return s.error();
        if (c == 2)
          for (std::size_t k = 0; k < n; ++k) out.radiance[k * nd + d] = one[k];
      }
  }
  return out;
}

}  // namespace penumbra::spaceland::atlas
