// Reading and checking 2D scene documents (docs/scene-format.md, version 1).
//
// Parsing has two steps: the JSON is walked for structure and types (unknown keys, missing
// fields, wrong types, non-finite numbers), giving a SceneDesc; then the layers are loaded and
// `validate` checks every value range on the SceneDesc. Range rules therefore live in one place
// and a file and a scene built in code get the same messages.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>

#include "io/image_io.hpp"
#include "io/json_reader.hpp"
#include "penumbra/flatland/scene.hpp"

namespace penumbra::flatland {
namespace {

using io::describe;
using io::expected_text;
using io::fail;
using io::format_number;
using io::in_range;
using io::Range;
using nlohmann::json;

void check_float(const std::string& file, const std::string& path, float v, Range r) {
  if (!std::isfinite(v)) fail(file, path, "expected a finite number, found " + format_number(v));
  if (!in_range(v, r))
    fail(file, path, std::string("expected ") + expected_text(r) + ", found " + format_number(v));
}

void check_rgb(const std::string& file, const std::string& path, const Rgb& c, Range r) {
  check_float(file, path + "[0]", c.r, r);
  check_float(file, path + "[1]", c.g, r);
  check_float(file, path + "[2]", c.b, r);
}

void check_point(const std::string& file, const std::string& path, const std::array<float, 2>& p) {
  check_float(file, path + "[0]", p[0], Range::any);
  check_float(file, path + "[1]", p[1], Range::any);
}

void check_grid_side(const std::string& file, const std::string& path, int v) {
  if (v < 1 || v > kMaxGridSide)
    fail(file, path,
         "expected an integer in 1.." + std::to_string(kMaxGridSide) + ", found " +
             std::to_string(v));
}

// Checks `channels` interleaved values per pixel of a w x h layer; reports the first bad pixel.
void check_layer_values(const std::string& file, const std::string& name, const float* v, int width,
                        int height, int channels, Range r) {
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) {
        float value = v[(std::size_t(y) * width + x) * channels + c];
        if (in_range(value, r)) continue;
        std::string what = std::string("expected finite values ") +
                           (r == Range::unit ? "in [0, 1]" : ">= 0") + ", found " +
                           format_number(value) + " at pixel (" + std::to_string(x) + ", " +
                           std::to_string(y) + ")";
        if (channels > 1) what += " channel " + std::to_string(c);
        fail(file, "layers." + name, what);
      }
    }
  }
}

void check_layer_size(const std::string& file, const std::string& name, int w, int h,
                      const SceneDesc& desc) {
  if (w != desc.width || h != desc.height)
    fail(file, "layers." + name,
         "expected an image of " + std::to_string(desc.width) + "x" + std::to_string(desc.height) +
             " pixels (the grid size), found " + std::to_string(w) + "x" + std::to_string(h));
}

void check_material(const std::string& file, const std::string& path, const Material& m) {
  check_rgb(file, path + ".emission", m.emission, Range::nonneg);
  check_float(file, path + ".opacity", m.opacity, Range::unit);
  check_rgb(file, path + ".albedo", m.albedo, Range::unit);
}

void check_desc(const SceneDesc& desc) {
  const std::string& file = desc.source;
  check_grid_side(file, "width", desc.width);
  check_grid_side(file, "height", desc.height);
  check_rgb(file, "environment", desc.environment, Range::nonneg);

  const Layers& layers = desc.layers;
  if (layers.emission) {
    check_layer_size(file, "emission", layers.emission->width(), layers.emission->height(), desc);
    check_layer_values(file, "emission", layers.emission->data(), desc.width, desc.height, 3,
                       Range::nonneg);
  }
  if (layers.opacity) {
    const std::size_t cells = std::size_t(desc.width) * desc.height;
    if (layers.opacity->size() != cells)
      fail(file, "layers.opacity",
           "expected " + std::to_string(cells) + " values (" + std::to_string(desc.width) + "x" +
               std::to_string(desc.height) + "), found " + std::to_string(layers.opacity->size()));
    check_layer_values(file, "opacity", layers.opacity->data(), desc.width, desc.height, 1,
                       Range::unit);
  }
  if (layers.albedo) {
    check_layer_size(file, "albedo", layers.albedo->width(), layers.albedo->height(), desc);
    check_layer_values(file, "albedo", layers.albedo->data(), desc.width, desc.height, 3,
                       Range::unit);
  }

  for (std::size_t i = 0; i < desc.shapes.size(); ++i) {
    const Shape& shape = desc.shapes[i];
    const std::string path = "shapes[" + std::to_string(i) + "]";
    if (const auto* c = std::get_if<Circle>(&shape.geometry)) {
      check_point(file, path + ".center", c->center);
      check_float(file, path + ".radius", c->radius, Range::positive);
    } else if (const auto* b = std::get_if<Box>(&shape.geometry)) {
      check_point(file, path + ".center", b->center);
      check_float(file, path + ".size[0]", b->size[0], Range::positive);
      check_float(file, path + ".size[1]", b->size[1], Range::positive);
      check_float(file, path + ".angle", b->angle, Range::any);
    } else if (const auto* s = std::get_if<Segment>(&shape.geometry)) {
      check_point(file, path + ".a", s->a);
      check_point(file, path + ".b", s->b);
      check_float(file, path + ".width", s->width, Range::positive);
    } else if (const auto* p = std::get_if<Polygon>(&shape.geometry)) {
      if (p->points.size() < 3)
        fail(file, path + ".points",
             "expected at least 3 [x, y] points, found " + std::to_string(p->points.size()));
      for (std::size_t k = 0; k < p->points.size(); ++k)
        check_point(file, path + ".points[" + std::to_string(k) + "]", p->points[k]);
    }
    check_material(file, path, shape.material);
  }
}

// ---- The JSON walk: structure and types. ----

class Walker : public io::JsonReader {
 public:
  using JsonReader::JsonReader;

  std::array<float, 2> size2(const json& j, const std::string& path) const {
    if (!j.is_array() || j.size() != 2) expected(path, "a [w, h] pair of numbers > 0", j);
    return {number(j[0], path + "[0]", Range::positive),
            number(j[1], path + "[1]", Range::positive)};
  }

  Shape shape(const json& j, const std::string& path) const {
    if (!j.is_object()) expected(path, "a shape object", j);
    const char* kTypes = "one of circle, box, segment, polygon";
    const json& type_j = require(j, path, "type", std::string("a shape type, ") + kTypes);
    if (!type_j.is_string())
      expected(path + ".type", std::string("a shape type, ") + kTypes, type_j);
    const std::string type = type_j.get<std::string>();

    Shape s;
    if (type == "circle") {
      check_keys(j, path, {"type", "center", "radius", "emission", "opacity", "albedo"});
      Circle c;
      c.center = point(require(j, path, "center", "an [x, y] pair of numbers"), path + ".center");
      c.radius = number(require(j, path, "radius", expected_text(Range::positive)),
                        path + ".radius", Range::positive);
      s.geometry = c;
    } else if (type == "box") {
      check_keys(j, path, {"type", "center", "size", "angle", "emission", "opacity", "albedo"});
      Box b;
      b.center = point(require(j, path, "center", "an [x, y] pair of numbers"), path + ".center");
      b.size = size2(require(j, path, "size", "a [w, h] pair of numbers > 0"), path + ".size");
      if (j.contains("angle")) b.angle = number(j["angle"], path + ".angle", Range::any);
      s.geometry = b;
    } else if (type == "segment") {
      check_keys(j, path, {"type", "a", "b", "width", "emission", "opacity", "albedo"});
      Segment g;
      g.a = point(require(j, path, "a", "an [x, y] pair of numbers"), path + ".a");
      g.b = point(require(j, path, "b", "an [x, y] pair of numbers"), path + ".b");
      g.width = number(require(j, path, "width", expected_text(Range::positive)), path + ".width",
                       Range::positive);
      s.geometry = g;
    } else if (type == "polygon") {
      check_keys(j, path, {"type", "points", "emission", "opacity", "albedo"});
      const std::string what = "an array of at least 3 [x, y] points";
      const json& pts = require(j, path, "points", what);
      if (!pts.is_array() || pts.size() < 3) expected(path + ".points", what, pts);
      Polygon p;
      for (std::size_t k = 0; k < pts.size(); ++k)
        p.points.push_back(point(pts[k], path + ".points[" + std::to_string(k) + "]"));
      s.geometry = std::move(p);
    } else {
      fail_at(path + ".type", "unknown shape type \"" + type + "\", expected " + kTypes);
    }

    if (j.contains("emission"))
      s.material.emission = rgb(j["emission"], path + ".emission", Range::nonneg);
    if (j.contains("opacity"))
      s.material.opacity = number(j["opacity"], path + ".opacity", Range::unit);
    if (j.contains("albedo")) s.material.albedo = rgb(j["albedo"], path + ".albedo", Range::unit);
    return s;
  }
};

// One decoded layer file: RGB (grey expanded) or its first channel.
ImageRgb load_rgb_layer(const io::RawImage& raw, bool srgb_decode, float scale) {
  ImageRgb out(raw.width, raw.height);
  const int ch = raw.channels;
  const std::size_t n = std::size_t(raw.width) * raw.height;
  float* dst = out.data();
  for (std::size_t i = 0; i < n; ++i) {
    const float* p = &raw.pixels[i * ch];
    float rgb[3] = {p[0], ch >= 3 ? p[1] : p[0], ch >= 3 ? p[2] : p[0]};
    for (int c = 0; c < 3; ++c) {
      float v = srgb_decode ? io::srgb_to_linear(rgb[c]) : rgb[c];
      dst[i * 3 + c] = v * scale;
    }
  }
  return out;
}

std::vector<float> load_first_channel(const io::RawImage& raw) {
  const std::size_t n = std::size_t(raw.width) * raw.height;
  std::vector<float> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = raw.pixels[i * raw.channels];
  return out;
}

SceneDesc parse_or_throw(std::string_view text, const std::string& path) {
  const json doc = io::parse_json(text, path);

  Walker w(path);
  SceneDesc desc;
  desc.source = path;
  if (!doc.is_object()) w.expected("(document)", "a JSON object", doc);

  // The version first: a document of another version may have other keys.
  const json& version = w.require(doc, "", "penumbra", "the format version 1");
  if (!version.is_number_integer())
    w.expected("penumbra", "the format version, the integer 1", version);
  bool is_one = version.is_number_unsigned() ? version.get<std::uint64_t>() == 1
                                             : version.get<std::int64_t>() == 1;
  if (!is_one) w.fail_at("penumbra", "unknown version, expected 1, found " + version.dump());

  w.check_keys(doc, "", {"penumbra", "width", "height", "environment", "layers", "shapes"});
  desc.width =
      w.integer(w.require(doc, "", "width", "an integer in 1..16384"), "width", 1, kMaxGridSide);
  desc.height =
      w.integer(w.require(doc, "", "height", "an integer in 1..16384"), "height", 1, kMaxGridSide);
  if (doc.contains("environment"))
    desc.environment = w.rgb(doc["environment"], "environment", Range::nonneg);

  std::string layer_files[3];  // emission, opacity, albedo
  static const char* kLayerNames[3] = {"emission", "opacity", "albedo"};
  float emission_scale = 1;
  if (doc.contains("layers")) {
    const json& layers = doc["layers"];
    if (!layers.is_object()) w.expected("layers", "an object", layers);
    w.check_keys(layers, "layers", {"emission", "opacity", "albedo", "emission_scale"});
    for (int k = 0; k < 3; ++k) {
      if (!layers.contains(kLayerNames[k])) continue;
      std::string lpath = std::string("layers.") + kLayerNames[k];
      layer_files[k] = w.string(layers[kLayerNames[k]], lpath, "an image file name");
      if (layer_files[k].empty()) w.fail_at(lpath, "expected an image file name, found \"\"");
    }
    if (layers.contains("emission_scale")) {
      emission_scale = w.number(layers["emission_scale"], "layers.emission_scale", Range::nonneg);
      check_float(path, "layers.emission_scale", emission_scale, Range::nonneg);
    }
  }

  if (doc.contains("shapes")) {
    const json& shapes = doc["shapes"];
    if (!shapes.is_array()) w.expected("shapes", "an array of shapes", shapes);
    for (std::size_t i = 0; i < shapes.size(); ++i)
      desc.shapes.push_back(w.shape(shapes[i], "shapes[" + std::to_string(i) + "]"));
  }

  // Layers, relative to the scene file's directory.
  const std::filesystem::path base = std::filesystem::path(path).parent_path();
  for (int k = 0; k < 3; ++k) {
    if (layer_files[k].empty()) continue;
    const std::string name = kLayerNames[k];
    std::filesystem::path file(layer_files[k]);
    if (file.is_relative()) file = base / file;
    auto raw = io::read_image(file.string(), desc.width, desc.height);
    if (!raw) w.fail_at("layers." + name, "cannot load the image: " + raw.error().message);
    if (raw->channels < 1 ||
        raw->pixels.size() != std::size_t(raw->width) * raw->height * raw->channels)
      w.fail_at("layers." + name, "the image reader returned malformed pixels");
    check_layer_size(path, name, raw->width, raw->height, desc);
    if (k == 0) {
      desc.layers.emission = load_rgb_layer(*raw, raw->integer_png, emission_scale);
      desc.layers.emission_scale = emission_scale;
    } else if (k == 1) {
      // Opacity is a linear fraction, never sRGB-decoded.
      desc.layers.opacity = load_first_channel(*raw);
    } else {
      desc.layers.albedo = load_rgb_layer(*raw, raw->integer_png, 1);
    }
  }

  check_desc(desc);
  return desc;
}

}  // namespace

Expected<SceneDesc> parse_scene(std::string_view json_text, const std::string& path) {
  try {
    return parse_or_throw(json_text, path);
  } catch (const io::JsonFailure& f) {
    return Error{f.message};
  } catch (const std::exception& e) {  // e.g. allocation failure: still no throw across the API
    return Error{path + ": " + e.what()};
  }
}

Expected<SceneDesc> load_scene(const std::string& path) {
  Expected<std::string> text = io::read_text(path, "the scene file");
  if (!text) return text.error();
  return parse_scene(*text, path);
}

Status validate(const SceneDesc& desc) {
  try {
    check_desc(desc);
  } catch (const io::JsonFailure& f) {
    return Error{f.message};
  }
  return {};
}

}  // namespace penumbra::flatland
