// The 2D scene: the document of docs/scene-format (version 1) and its rasterised grid.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/image.hpp"

namespace penumbra::flatland {

// Largest width or height the format allows.
inline constexpr int kMaxGridSide = 16384;

struct Material {
  Rgb emission{};     // radiance emitted by the material
  float opacity = 1;  // fraction absorbed along one cell length, in [0, 1]; 1 is opaque
  Rgb albedo{};       // diffuse reflectance, used when more than one bounce is asked for
};

struct Circle {
  std::array<float, 2> center{};
  float radius = 1;
};
struct Box {
  std::array<float, 2> center{};
  std::array<float, 2> size{1, 1};
  float angle = 0;  // degrees, from +x towards +y
};
struct Segment {
  std::array<float, 2> a{}, b{};
  float width = 1;  // diameter of the capsule
};
struct Polygon {
  std::vector<std::array<float, 2>> points;  // at least 3, even-odd rule
};

struct Shape {
  std::variant<Circle, Box, Segment, Polygon> geometry;
  Material material;
};

// Image layers, one value per cell, already decoded to linear values (row 0 at the top).
struct Layers {
  std::optional<ImageRgb> emission;           // linear radiance, emission_scale applied
  std::optional<std::vector<float>> opacity;  // width * height values in [0, 1]
  std::optional<ImageRgb> albedo;             // in [0, 1]
  float emission_scale = 1;  // the file's `emission_scale`, for programs that write it back
};

// The scene as written: what a file holds, or what a program builds in code.
struct SceneDesc {
  int width = 0, height = 0;
  Rgb environment{};
  Layers layers;
  std::vector<Shape> shapes;
  std::string source = "<code>";  // file name used in error messages
};

// The rasterised scene every method reads: per-cell emission, opacity and albedo.
struct Scene {
  int width = 0, height = 0;
  Rgb environment{};
  std::vector<float> emission;  // 3 per cell, linear radiance
  std::vector<float> opacity;   // 1 per cell, in [0, 1]; 1 is opaque
  std::vector<float> albedo;    // 3 per cell

  std::size_t cells() const { return std::size_t(width) * height; }
  std::size_t index(int x, int y) const { return std::size_t(y) * width + x; }
};

// Parses a version-1 document. `path` names the file in messages and anchors relative layer
// paths. Every rule of the format is checked; a message names the file and the JSON path.
Expected<SceneDesc> parse_scene(std::string_view json_text, const std::string& path);

// Reads and parses a scene file.
Expected<SceneDesc> load_scene(const std::string& path);

// Checks a scene built in code against the same rules as a file.
Status validate(const SceneDesc& desc);

// Validates, then draws layers and shapes into cells with anti-aliased coverage.
Expected<Scene> build_scene(const SceneDesc& desc);

// The built-in scene that `penumbra render` draws when no file is given.
SceneDesc default_scene();

// The image layers a written scene file names: paths as written in the file, relative to it
// (empty: none), and the `emission_scale` written beside them.
struct LayerFiles {
  std::string emission, opacity, albedo;
  float emission_scale = 1;
};

// Writes `desc` as a version-1 document: one key a line, one shape a line, numbers as the
// shortest text that reads back as the same float, so parse_scene(scene_json(d)) gives back d's
// width, height, environment and shapes bit for bit (-0 is written "-0.0"). Material fields and
// `angle` are written only where they differ from the format's defaults. `layers` is written
// from `layers` alone: a SceneDesc's decoded images are not written (the caller writes the
// image files). `description`, when not empty, is written as the ignored "description" key.
// The caller validates `desc` first: a value validate() refuses (NaN, infinity) is not valid
// JSON and is written as it is.
std::string scene_json(const SceneDesc& desc, const LayerFiles& layers = {},
                       const std::string& description = "");

}  // namespace penumbra::flatland
