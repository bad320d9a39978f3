// Writing 2D scene documents (docs/scene-format.md, version 1): the inverse of parse_scene for
// everything a SceneDesc holds except its decoded layers.
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "io/json_reader.hpp"
#include "penumbra/flatland/scene.hpp"

namespace penumbra::flatland {
namespace {

// Shortest text that reads back as the same float. The reader takes "-0" for the integer 0, so
// negative zero gets a fraction to keep its sign.
std::string num(float v) {
  if (v == 0 && std::signbit(v)) return "-0.0";
  const std::string text = io::format_number(v);
  // The reader parses a double and rounds it to float. Rounding twice moves one float pair
  // (+-7.038531e-26, found by trying every float) a step away; the double's text does not.
  double back = 0;
  std::from_chars(text.data(), text.data() + text.size(), back);
  if (std::bit_cast<std::uint32_t>(static_cast<float>(back)) != std::bit_cast<std::uint32_t>(v))
    return io::format_number(static_cast<double>(v));
  return text;
}

// Joins pieces of text. (GCC 12 warns falsely, -Wrestrict, on "literal" + std::string&&.)
std::string cat(std::initializer_list<std::string_view> parts) {
  std::string s;
  for (std::string_view p : parts) s += p;
  return s;
}

std::string point(std::array<float, 2> p) {
  return cat({"[", num(p[0]), ", ", num(p[1]), "]"});
}
std::string rgb(Rgb c) {
  return cat({"[", num(c.r), ", ", num(c.g), ", ", num(c.b), "]"});
}

// Defaults are compared bit for bit: a -0 left out would read back as +0.
bool same_bits(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}
bool is_black(Rgb c) {
  return same_bits(c.r, 0) && same_bits(c.g, 0) && same_bits(c.b, 0);
}

std::string geometry_json(const Circle& c) {
  return cat(
      {R"("type": "circle", "center": )", point(c.center), R"(, "radius": )", num(c.radius)});
}
std::string geometry_json(const Box& b) {
  const bool angled = !same_bits(b.angle, 0);
  return cat({R"("type": "box", "center": )", point(b.center), R"(, "size": )", point(b.size),
              angled ? R"(, "angle": )" : "", angled ? num(b.angle) : ""});
}
std::string geometry_json(const Segment& g) {
  return cat({R"("type": "segment", "a": )", point(g.a), R"(, "b": )", point(g.b), R"(, "width": )",
              num(g.width)});
}
std::string geometry_json(const Polygon& p) {
  std::string s = R"("type": "polygon", "points": [)";
  for (std::size_t i = 0; i < p.points.size(); ++i) s += cat({i ? ", " : "", point(p.points[i])});
  return s + "]";
}

std::string shape_json(const Shape& shape) {
  std::string s = "{ ";
  s += std::visit([](const auto& g) { return geometry_json(g); }, shape.geometry);
  const Material& m = shape.material;
  if (!is_black(m.emission)) s += cat({R"(, "emission": )", rgb(m.emission)});
  if (!same_bits(m.opacity, 1)) s += cat({R"(, "opacity": )", num(m.opacity)});
  if (!is_black(m.albedo)) s += cat({R"(, "albedo": )", rgb(m.albedo)});
  return s + " }";
}

// A JSON string. Bytes from 0x80 up are copied as they are (UTF-8 stays UTF-8).
std::string json_string(std::string_view text) {
  std::string s = "\"";
  for (char ch : text) {
    switch (ch) {
      case '"':
        s += "\\\"";
        break;
      case '\\':
        s += "\\\\";
        break;
      case '\n':
        s += "\\n";
        break;
      case '\t':
        s += "\\t";
        break;
      case '\r':
        s += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(ch) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(ch));
          s += buf;
        } else {
          s += ch;
        }
    }
  }
  return s + "\"";
}

}  // namespace

std::string scene_json(const SceneDesc& desc, const LayerFiles& layers,
                       const std::string& description) {
  std::string s = "{\n  \"penumbra\": 1";
  if (!description.empty()) s += cat({",\n  \"description\": ", json_string(description)});
  s += cat({",\n  \"width\": ", std::to_string(desc.width), ",\n  \"height\": ",
            std::to_string(desc.height), ",\n  \"environment\": ", rgb(desc.environment)});
  std::vector<std::string> entries;
  if (!layers.emission.empty())
    entries.push_back(cat({R"("emission": )", json_string(layers.emission)}));
  if (!layers.opacity.empty())
    entries.push_back(cat({R"("opacity": )", json_string(layers.opacity)}));
  if (!layers.albedo.empty()) entries.push_back(cat({R"("albedo": )", json_string(layers.albedo)}));
  if (!same_bits(layers.emission_scale, 1))
    entries.push_back(cat({R"("emission_scale": )", num(layers.emission_scale)}));
  if (!entries.empty()) {
    s += ",\n  \"layers\": {\n";
    for (std::size_t i = 0; i < entries.size(); ++i)
      s += cat({"    ", entries[i], i + 1 < entries.size() ? ",\n" : "\n"});
    s += "  }";
  }
  if (!desc.shapes.empty()) {
    s += ",\n  \"shapes\": [\n";
    for (std::size_t i = 0; i < desc.shapes.size(); ++i)
      s += cat({"    ", shape_json(desc.shapes[i]), i + 1 < desc.shapes.size() ? ",\n" : "\n"});
    s += "  ]";
  }
  return s + "\n}\n";
}

}  // namespace penumbra::flatland
