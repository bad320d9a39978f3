// The painter's canvas: brush strokes, undo, saving, and stroke files.
#include "flatland/paint/canvas.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/parallel.hpp"
#include "flatland/scene/rasterize.hpp"
#include "io/image_io.hpp"
#include "io/json_reader.hpp"
#include "io/path_util.hpp"
#include "penumbra/flatland/render.hpp"

namespace penumbra::flatland::paint {

namespace {

using json = nlohmann::json;

// Versions come from one counter, so two canvases (a loaded one replacing another) never share
// one and the solver always sees the change.
std::atomic<std::uint64_t> g_versions{0};

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// The value a layer file holds for `v`: emission and albedo as sRGB codes, opacity linear.
float snap_srgb(float v, float scale) {
  return decode_srgb16(encode_srgb16(v / scale)) * scale;
}
float snap_linear(float v) {
  return decode_linear16(encode_linear16(v));
}

// Cell i of s moved to the layer codes, emission relative to `scale`.
void snap_cell(Scene& s, std::size_t i, float scale) {
  s.opacity[i] = snap_linear(s.opacity[i]);
  for (std::size_t k = 3 * i; k < 3 * i + 3; ++k) {
    s.emission[k] = snap_srgb(s.emission[k], scale);
    s.albedo[k] = snap_srgb(s.albedo[k], 1.0f);
  }
}

}  // namespace

const char* to_string(Tool t) {
  switch (t) {
    case Tool::light:
      return "light";
    case Tool::wall:
      return "wall";
    case Tool::fog:
      return "fog";
    case Tool::erase:
      return "erase";
  }
  return "?";
}

std::uint16_t encode_srgb16(float linear) {
  return std::uint16_t(std::lround(io::linear_to_srgb(linear) * 65535.0f));
}
float decode_srgb16(std::uint16_t code) {
  return io::srgb_to_linear(code / 65535.0f);  // as the scene loader decodes a PNG layer
}
std::uint16_t encode_linear16(float v) {
  return std::uint16_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 65535.0f));
}
float decode_linear16(std::uint16_t code) {
  return code / 65535.0f;
}

Material Brush::material() const {
  Material m;
  switch (tool) {
    case Tool::light:
      m.emission = {color.r * intensity, color.g * intensity, color.b * intensity};
      m.opacity = 1;
      break;
    case Tool::wall:
      m.opacity = 1;
      m.albedo = color;
      break;
    case Tool::fog:
      m.opacity = opacity;
      m.albedo = color;
      break;
    case Tool::erase:
      m.opacity = 0;
      break;
  }
  return m;
}

// ---- canvas -------------------------------------------------------------------------------

Expected<Canvas> Canvas::blank(int width, int height, float emission_scale) {
  if (width < 1 || height < 1 || width > kMaxCanvasSide || height > kMaxCanvasSide)
    return Error{"canvas: expected 1.." + std::to_string(kMaxCanvasSide) + " cells a side, found " +
                 std::to_string(width) + "x" + std::to_string(height)};
  if (!(emission_scale > 0) || !std::isfinite(emission_scale))
    return Error{"canvas: emission scale must be a finite number > 0"};
  Canvas c;
  c.scene_.width = width;
  c.scene_.height = height;
  const std::size_t n = c.scene_.cells();
  c.scene_.emission.assign(3 * n, 0.0f);
  c.scene_.opacity.assign(n, 0.0f);
  c.scene_.albedo.assign(3 * n, 0.0f);
  c.coverage_.assign(n, 0.0f);
  c.emission_scale_ = emission_scale;
  c.undo_limit_ =
      std::clamp<std::size_t>(kUndoBytes / scene_bytes(width, height), 1, kMaxUndoSteps);
  c.touch();
  return c;
}

Expected<Canvas> Canvas::from_scene(const SceneDesc& desc, float min_scale) {
  if (desc.width > kMaxCanvasSide || desc.height > kMaxCanvasSide)
    return Error{desc.source + ": the painter edits grids up to " + std::to_string(kMaxCanvasSide) +
                 " cells a side, this one is " + std::to_string(desc.width) + "x" +
                 std::to_string(desc.height)};
  Expected<Scene> built = build_scene(desc);
  if (!built) return built.error();
  float brightest = 0;
  for (float e : built->emission) brightest = std::max(brightest, e);
  if (!(min_scale >= 0) || !std::isfinite(min_scale))
    return Error{"canvas: emission scale must be a finite number > 0"};
  // A painting read back keeps its scale, so its cells stay on the same codes.
  float scale = desc.layers.emission ? desc.layers.emission_scale : 0.0f;
  if (!(scale >= brightest) || !(scale >= min_scale) || !(scale > 0)) {
    scale = min_scale > 0 ? min_scale : kDefaultEmissionScale;
    while (scale < brightest && scale < 1e30f) scale *= 2;
  }
  if (!(scale >= brightest))
    return Error{desc.source + ": its brightest cell (" + number_text(brightest) +
                 ") is more than the painter holds (1e30)"};
  Expected<Canvas> c = blank(desc.width, desc.height, scale);
  if (!c) return c.error();
  Scene& s = c->scene_;
  s = std::move(*built);
  parallel_for(s.height, [&](int y) {
    for (std::size_t i = s.index(0, y), end = i + std::size_t(s.width); i < end; ++i)
      snap_cell(s, i, scale);
  });
  return c;
}

Status Canvas::check(const Brush& b, const std::string& where) const {
  auto bad = [&](const std::string& what) { return Status(Error{where + "." + what}); };
  if (!(b.radius >= 0.5f) || !(b.radius <= kMaxBrushRadius))
    return bad("radius: expected 0.5.." + std::to_string(int(kMaxBrushRadius)) + " cells");
  for (float c : {b.color.r, b.color.g, b.color.b})
    if (!(c >= 0.0f) || !(c <= 1.0f)) return bad("color: expected components in [0, 1]");
  if (b.tool == Tool::light) {
    const float top = std::max({b.color.r, b.color.g, b.color.b}) * b.intensity;
    if (!(b.intensity >= 0.0f) || !(top <= emission_scale_))
      return bad("intensity: expected color * intensity in [0, " + number_text(emission_scale_) +
                 "] (the canvas's emission scale; start the painter with a larger "
                 "--emission-scale)");
  }
  if (b.tool == Tool::fog && (!(b.opacity > 0.0f) || !(b.opacity < 1.0f)))
    return bad("opacity: expected a fraction in (0, 1) (1 is a wall)");
  return {};
}

Status Canvas::begin_stroke(const Brush& brush, float x, float y) {
  if (Status s = check(brush); !s) return s;
  if (!std::isfinite(x) || !std::isfinite(y)) return Error{"brush: position is not finite"};
  if (stroking_) end_stroke();
  brush_ = brush;
  material_ = brush.material();
  snapped_ = material_;
  snapped_.opacity = snap_linear(material_.opacity);
  for (float* v : {&snapped_.emission.r, &snapped_.emission.g, &snapped_.emission.b})
    *v = snap_srgb(*v, emission_scale_);
  for (float* v : {&snapped_.albedo.r, &snapped_.albedo.g, &snapped_.albedo.b})
    *v = snap_srgb(*v, 1.0f);
  before_ = snapshot();
  stroking_ = true;
  last_x_ = x;
  last_y_ = y;
  cover_segment(x, y, x, y);
  return {};
}

void Canvas::extend_stroke(float x, float y) {
  if (!stroking_ || !std::isfinite(x) || !std::isfinite(y)) return;
  cover_segment(last_x_, last_y_, x, y);
  last_x_ = x;
  last_y_ = y;
}

void Canvas::end_stroke() {
  if (!stroking_) return;
  stroking_ = false;
  std::fill(coverage_.begin(), coverage_.end(), 0.0f);
  push_undo(std::move(before_));
  before_ = {};
}

Status Canvas::apply(const Stroke& stroke, const std::string& where) {
  if (stroke.points.empty()) return Error{where + ".points: expected at least one point"};
  if (Status s = check(stroke.brush, where); !s) return s;
  if (Status s = begin_stroke(stroke.brush, stroke.points[0][0], stroke.points[0][1]); !s) return s;
  for (std::size_t i = 1; i < stroke.points.size(); ++i)
    extend_stroke(stroke.points[i][0], stroke.points[i][1]);
  end_stroke();
  return {};
}

// Coverage of a cell is 1 within the radius of the segment, falling to 0 over one cell (about
// its covered area): the stroke's coverage is the largest over its segments, so joints are not
// covered twice.
void Canvas::cover_segment(float ax, float ay, float bx, float by) {
  const float r = brush_.radius;
  // Only the part of the segment within r + 1 of the grid can cover a cell: clip it (in double,
  // Liang-Barsky), so that points far off the grid leave the float arithmetic below exact. A
  // clipped end lies on its clipping edge exactly; only its other coordinate is interpolated.
  {
    const double lo[2] = {-double(r) - 1, -double(r) - 1};
    const double hi[2] = {scene_.width + double(r) + 1, scene_.height + double(r) + 1};
    const double a[2] = {ax, ay}, d[2] = {double(bx) - ax, double(by) - ay};
    double t0 = 0, t1 = 1;
    int e0 = -1, e1 = -1;  // the edges (2 axis + side) that clipped each end
    for (int axis = 0; axis < 2; ++axis) {
      for (int side = 0; side < 2; ++side) {
        const double p = side == 0 ? -d[axis] : d[axis];
        const double q = side == 0 ? a[axis] - lo[axis] : hi[axis] - a[axis];
        if (p == 0) {
          if (q < 0) return;  // parallel to this edge and outside it
          continue;
        }
        const double t = q / p;
        if (p < 0 && t > t0) t0 = t, e0 = 2 * axis + side;
        if (p > 0 && t < t1) t1 = t, e1 = 2 * axis + side;
      }
    }
    if (t0 > t1) return;
    // The clipped end lies on the edge; its other coordinate follows the line from whichever
    // end is nearer the edge (from a far end, a + t d would cancel to nothing).
    const double b2[2] = {bx, by};
    auto end_point = [&](int edge, float& x, float& y) {
      if (edge < 0) return;  // not clipped
      const int axis = edge / 2, other = 1 - axis;
      const double e = edge % 2 == 0 ? lo[axis] : hi[axis];
      const double* base = std::fabs(e - a[axis]) <= std::fabs(e - b2[axis]) ? a : b2;
      double c[2];
      c[axis] = e;
      c[other] = base[other] + (e - base[axis]) * (d[other] / d[axis]);
      x = float(c[0]), y = float(c[1]);
    };
    float cx0 = ax, cy0 = ay, cx1 = bx, cy1 = by;
    end_point(e0, cx0, cy0);
    end_point(e1, cx1, cy1);
    ax = cx0, ay = cy0, bx = cx1, by = cy1;
  }
  // Bounds clamped as floats first: points far off the grid must not overflow an int.
  auto lo = [&](float a, float b, int n) {
    return int(std::clamp(std::floor(std::min(a, b) - r - 1), 0.0f, float(n)));
  };
  auto hi = [&](float a, float b, int n) {
    return int(std::clamp(std::ceil(std::max(a, b) + r + 1), -1.0f, float(n - 1)));
  };
  const int x0 = lo(ax, bx, scene_.width), x1 = hi(ax, bx, scene_.width);
  const int y0 = lo(ay, by, scene_.height), y1 = hi(ay, by, scene_.height);
  if (x0 > x1 || y0 > y1) return;
  const float dx = bx - ax, dy = by - ay, len2 = dx * dx + dy * dy;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const float px = x + 0.5f - ax, py = y + 0.5f - ay;
      const float t = len2 > 0 ? std::clamp((px * dx + py * dy) / len2, 0.0f, 1.0f) : 0.0f;
      const float d = std::hypot(px - t * dx, py - t * dy);
      const float cover = std::clamp(r + 0.5f - d, 0.0f, 1.0f);
      const std::size_t i = scene_.index(x, y);
      if (cover <= coverage_[i]) continue;
      coverage_[i] = cover;
      if (cover >= 1.0f) {  // fully covered: the brush's material, already on the codes
        blend(scene_, i, 1.0f, snapped_);
        continue;
      }
      // Partly covered: the cell as it was before the stroke, under the brush's material by
      // the rasteriser's rule for edge cells, then moved to the layer codes.
      std::copy_n(&before_.emission[3 * i], 3, &scene_.emission[3 * i]);
      std::copy_n(&before_.albedo[3 * i], 3, &scene_.albedo[3 * i]);
      scene_.opacity[i] = before_.opacity[i];
      blend(scene_, i, blend_fraction(cover, material_), material_);
      snap_cell(scene_, i, emission_scale_);
    }
  }
  touch();
}

void Canvas::touch() {
  version_ = ++g_versions;
}

Canvas::Cells Canvas::snapshot() const {
  return {scene_.emission, scene_.opacity, scene_.albedo};
}

void Canvas::restore(Cells&& cells) {
  scene_.emission = std::move(cells.emission);
  scene_.opacity = std::move(cells.opacity);
  scene_.albedo = std::move(cells.albedo);
  touch();
}

void Canvas::push_undo(Cells&& cells) {
  if (undo_.size() >= undo_limit_) undo_.erase(undo_.begin());
  undo_.push_back(std::move(cells));
}

bool Canvas::undo() {
  if (stroking_) end_stroke();
  if (undo_.empty()) return false;
  restore(std::move(undo_.back()));
  undo_.pop_back();
  return true;
}

void Canvas::clear() {
  if (stroking_) end_stroke();
  push_undo(snapshot());
  std::fill(scene_.emission.begin(), scene_.emission.end(), 0.0f);
  std::fill(scene_.opacity.begin(), scene_.opacity.end(), 0.0f);
  std::fill(scene_.albedo.begin(), scene_.albedo.end(), 0.0f);
  touch();
}

void Canvas::set_environment(Rgb environment) {
  scene_.environment = environment;
  touch();
}

Expected<std::vector<std::string>> Canvas::save_paths(const std::string& path) {
  namespace fs = std::filesystem;
  if (io::lowercase_extension(path) != ".json")
    return Error{path + ": a painting is saved as a scene file; use a .json name"};
  const fs::path target(path);
  const std::string stem = target.stem().string();
  std::vector<std::string> paths = {path};
  for (const char* layer : {".emission.png", ".opacity.png", ".albedo.png"})
    paths.push_back((target.parent_path() / (stem + layer)).string());
  return paths;
}

Expected<io::StagedFile> Canvas::stage_save(const std::vector<std::string>& paths,
                                            std::size_t k) const {
  if (k == 0) {
    auto name = [&](std::size_t i) { return std::filesystem::path(paths[i]).filename().string(); };
    SceneDesc desc;
    desc.width = scene_.width;
    desc.height = scene_.height;
    desc.environment = scene_.environment;
    return io::stage_text(paths[0], scene_json(desc, {name(1), name(2), name(3), emission_scale_}));
  }
  const std::size_t n = scene_.cells();
  const int channels = k == 2 ? 1 : 3;
  std::vector<std::uint16_t> codes(n * std::size_t(channels));
  for (std::size_t i = 0; i < codes.size(); ++i) {
    if (k == 1) codes[i] = encode_srgb16(scene_.emission[i] / emission_scale_);
    if (k == 2) codes[i] = encode_linear16(scene_.opacity[i]);
    if (k == 3) codes[i] = encode_srgb16(scene_.albedo[i]);
  }
  return io::stage_png16(paths[k], scene_.width, scene_.height, channels, codes);
}

Status Canvas::save(const std::string& path) const {
  Expected<std::vector<std::string>> paths = save_paths(path);
  if (!paths) return paths.error();
  return io::write_all(*paths, [&](std::size_t k) { return stage_save(*paths, k); });
}

// ---- stroke files -------------------------------------------------------------------------

namespace {

// A stroke file read with the scene loader's reader (its messages, keys and number rules).
class StrokeReader : public io::JsonReader {
 public:
  using JsonReader::JsonReader;

  Stroke stroke(const json& j, const std::string& where) const {
    if (!j.is_object()) expected(where, "a stroke object", j);
    check_keys(j, where, {"tool", "color", "intensity", "opacity", "radius", "points"});
    Stroke s;
    const char* kTools = "\"light\", \"wall\", \"fog\" or \"erase\"";
    const json& tool = require(j, where, "tool", kTools);
    const std::string name = tool.is_string() ? tool.get<std::string>() : "";
    if (name == "light")
      s.brush.tool = Tool::light;
    else if (name == "wall")
      s.brush.tool = Tool::wall;
    else if (name == "fog")
      s.brush.tool = Tool::fog;
    else if (name == "erase" || name == "eraser")
      s.brush.tool = Tool::erase;
    else
      expected(where + ".tool", kTools, tool);
    if (j.contains("color")) s.brush.color = rgb(j["color"], where + ".color", io::Range::unit);
    if (j.contains("intensity"))
      s.brush.intensity = number(j["intensity"], where + ".intensity", io::Range::nonneg);
    if (j.contains("opacity")) {
      s.brush.opacity = number(j["opacity"], where + ".opacity", io::Range::unit);
      if (!(s.brush.opacity > 0 && s.brush.opacity < 1))
        expected(where + ".opacity", "a fraction in (0, 1) (1 is a wall)", j["opacity"]);
    }
    if (j.contains("radius")) {
      s.brush.radius = number(j["radius"], where + ".radius", io::Range::any);
      if (!(s.brush.radius >= 0.5f && s.brush.radius <= kMaxBrushRadius))
        expected(where + ".radius", "0.5.." + std::to_string(int(kMaxBrushRadius)) + " cells",
                 j["radius"]);
    }
    const json& pts = require(j, where, "points", "a list of [x, y] cells");
    if (!pts.is_array() || pts.empty())
      expected(where + ".points", "a non-empty list of [x, y] cells", pts);
    for (std::size_t i = 0; i < pts.size(); ++i)
      s.points.push_back(point(pts[i], where + ".points[" + std::to_string(i) + "]"));
    return s;
  }
};

}  // namespace

Expected<StrokeFile> parse_strokes(std::string_view text, const std::string& path) {
  try {
    // The scene loader's parse: it also names a number out of range (1e999), which
    // nlohmann throws as out_of_range, not parse_error.
    const json doc = io::parse_json(text, path);
    const StrokeReader r(path);
    if (!doc.is_object()) r.expected("(document)", "an object with \"strokes\"", doc);
    r.check_keys(doc, "", {"strokes", "size"});
    const json& list = r.require(doc, "", "strokes", "a list of strokes");
    if (!list.is_array()) r.expected("strokes", "a list of strokes", list);
    StrokeFile out;
    if (doc.contains("size")) {
      const json& size = doc["size"];
      if (!size.is_array() || size.size() != 2)
        r.expected("size", "[width, height] in cells", size);
      out.width = r.integer(size[0], "size[0]", 1, kMaxGridSide);
      out.height = r.integer(size[1], "size[1]", 1, kMaxGridSide);
    }
    for (std::size_t i = 0; i < list.size(); ++i)
      out.strokes.push_back(r.stroke(list[i], "strokes[" + std::to_string(i) + "]"));
    return out;
  } catch (const io::JsonFailure& e) {
    return Error{e.message};
  } catch (const std::exception& e) {  // e.g. allocation failure: still no throw across the API
    return Error{path + ": " + e.what()};
  }
}

Expected<StrokeFile> load_strokes(const std::string& path) {
  Expected<std::string> text = io::read_text(path, "the stroke file");
  if (!text) return text.error();
  return parse_strokes(*text, path);
}

std::string strokes_json(const StrokeFile& file) {
  json list = json::array();
  for (const Stroke& s : file.strokes) {
    const Brush& b = s.brush;
    json j = {{"tool", to_string(b.tool)}, {"radius", b.radius}};
    if (b.tool != Tool::erase) j["color"] = {b.color.r, b.color.g, b.color.b};
    if (b.tool == Tool::light) j["intensity"] = b.intensity;
    if (b.tool == Tool::fog) j["opacity"] = b.opacity;
    json pts = json::array();
    for (const auto& p : s.points) pts.push_back({p[0], p[1]});
    j["points"] = std::move(pts);
    list.push_back(std::move(j));
  }
  json doc = {{"strokes", list}};
  if (file.width > 0) doc["size"] = {file.width, file.height};
  return doc.dump(1) + "\n";
}

}  // namespace penumbra::flatland::paint
