// The painter's document: a 2D scene edited with a brush, saved as a scene file with 16-bit PNG
// layers. Everything here runs without a window, so the tests drive it directly.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "io/image_io.hpp"
#include "penumbra/error.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/image.hpp"

namespace penumbra::flatland::paint {

// Largest grid side the painter edits (a canvas and its undo steps stay in memory).
inline constexpr int kMaxCanvasSide = 4096;
// Emission is held as 16-bit sRGB codes times this scale (the file's `emission_scale`).
inline constexpr float kDefaultEmissionScale = 64;
inline constexpr float kMaxBrushRadius = 256;
// Undo steps share this much memory, and are at most kMaxUndoSteps.
inline constexpr std::size_t kUndoBytes = std::size_t(512) << 20;
inline constexpr std::size_t kMaxUndoSteps = 200;

enum class Tool { light, wall, fog, erase };
const char* to_string(Tool t);

struct Brush {
  Tool tool = Tool::light;
  Rgb color{1, 1, 1};    // light: emitted colour; wall and fog: albedo
  float intensity = 1;   // light: emitted radiance is color * intensity
  float opacity = 0.1f;  // fog: fraction absorbed per cell length, in (0, 1)
  float radius = 3;      // cells; a cell is covered by its centre's distance to the stroke
  // What the brush leaves in a fully covered cell (the scene format's material).
  Material material() const;
};

struct Stroke {
  Brush brush;
  std::vector<std::array<float, 2>> points;  // grid cells, y down
};

// Stroke files: {"size": [w, h], "strokes": [{"tool", "color", "intensity", "opacity",
// "radius", "points"}]}; "size" (optional) is the grid they were painted on. Messages name the
// file and the JSON path of the offending value.
struct StrokeFile {
  std::vector<Stroke> strokes;
  int width = 0, height = 0;  // 0: not given
};
Expected<StrokeFile> parse_strokes(std::string_view json_text, const std::string& path);
Expected<StrokeFile> load_strokes(const std::string& path);
std::string strokes_json(const StrokeFile& file);

// The cell values of a canvas are always values a 16-bit PNG layer decodes to (the quantisation
// happens as the brush paints), so a saved painting reads back bit for bit.
class Canvas {
 public:
  // An empty (clear, black) canvas.
  static Expected<Canvas> blank(int width, int height,
                                float emission_scale = kDefaultEmissionScale);
  // A scene file's cells, rasterised; values move to the nearest 16-bit code. The emission scale
  // is the emission layer's own when it holds the brightest cell and is >= min_scale (a saved
  // painting reads back unchanged), else min_scale (0: kDefaultEmissionScale) doubled until it
  // holds the brightest cell.
  static Expected<Canvas> from_scene(const SceneDesc& desc, float min_scale = 0);

  const Scene& scene() const { return scene_; }
  int width() const { return scene_.width; }
  int height() const { return scene_.height; }
  float emission_scale() const { return emission_scale_; }
  // Changes on every edit: the solver renders again when it moves.
  std::uint64_t version() const { return version_; }

  // Refuses a brush the canvas cannot hold (a light brighter than the emission scale, a radius
  // or opacity out of range); `where` prefixes the message.
  Status check(const Brush& brush, const std::string& where = "brush") const;

  // A stroke: the brush covers the capsule of its radius around each segment between successive
  // points, so a fast mouse leaves no gaps. Overlapping parts of one stroke are covered once.
  Status begin_stroke(const Brush& brush, float x, float y);
  void extend_stroke(float x, float y);
  void end_stroke();
  bool in_stroke() const { return stroking_; }
  Status apply(const Stroke& stroke, const std::string& where = "stroke");

  bool undo();  // back to before the last stroke or clear; false when there is nothing to undo
  std::size_t undo_steps() const { return undo_.size(); }
  void clear();  // every cell clear and black (undoable)
  void set_environment(Rgb environment);

  // Writes `path` (JSON) and beside it <stem>.emission.png, <stem>.opacity.png and
  // <stem>.albedo.png (16-bit), all or nothing.
  Status save(const std::string& path) const;
  // The same in parts, for writing them together with other files: the four paths (the JSON
  // first), and file k of them staged (io::write_all publishes them).
  static Expected<std::vector<std::string>> save_paths(const std::string& path);
  Expected<io::StagedFile> stage_save(const std::vector<std::string>& paths, std::size_t k) const;

 private:
  Canvas() = default;
  struct Cells {
    std::vector<float> emission, opacity, albedo;
  };
  Cells snapshot() const;
  void restore(Cells&& cells);
  void push_undo(Cells&& cells);
  void cover_segment(float ax, float ay, float bx, float by);

  Scene scene_;
  float emission_scale_ = kDefaultEmissionScale;
  std::uint64_t version_ = 0;
  void touch();  // a new version, from a counter shared by all canvases
  std::vector<Cells> undo_;
  std::size_t undo_limit_ = 1;

  // The stroke in progress: the cells before it, its coverage so far, its brush.
  bool stroking_ = false;
  Brush brush_;
  Material material_;  // what the brush paints
  Material snapped_;   // the same on the layer codes: what a fully covered cell holds
  Cells before_;
  std::vector<float> coverage_;
  float last_x_ = 0, last_y_ = 0;
};

// The 16-bit codes of the layers and their decoding, as the scene loader does it.
std::uint16_t encode_srgb16(float linear);  // of a value in [0, 1]
float decode_srgb16(std::uint16_t code);
std::uint16_t encode_linear16(float v);
float decode_linear16(std::uint16_t code);

}  // namespace penumbra::flatland::paint
