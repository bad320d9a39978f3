// The painter's window: GLFW, OpenGL and Dear ImGui on the UI thread; the canvas, the brush and
// the strokes; a Worker renders on a thread of its own. The panel is drawn in panel.cpp.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "flatland/paint/canvas.hpp"
#include "paint/worker.hpp"
#include "paint_cmd.hpp"
#include "penumbra/penumbra.hpp"

struct GLFWwindow;

namespace painter {

constexpr float kPanelWidth = 340;
// The panel's height with its sections open as they start (it scrolls when more are open).
constexpr float kMinHeight = 780;

// The method's working memory plus the painter's copies of the canvas (the canvas, a stroke's
// starting cells, the worker's two) and its undo steps, against the method's memory limit.
penumbra::Status painter_memory(int w, int h, const penumbra::flatland::RenderOptions& o);

class Painter {
 public:
  Painter(const PaintArgs& args, penumbra::flatland::paint::Canvas canvas,
          std::vector<penumbra::flatland::paint::Stroke> replay);
  // Opens the window and paints until it is closed, the replay is done or a signal arrives;
  // writes the outputs. Exit code as run_paint's.
  int run();

 private:
  float zoom() const;
  void resize_window();
  void handle_input();
  void draw_panel();  // panel.cpp
  void submit();
  void upload(const Frame& f);
  int write_outputs(const std::vector<unsigned char>* shot, int shot_w, int shot_h);
  void replace_canvas(penumbra::flatland::paint::Canvas c);

  const PaintArgs& args_;
  penumbra::flatland::paint::Canvas canvas_;
  std::vector<penumbra::flatland::paint::Stroke> replay_;
  std::size_t replayed_ = 0;
  std::vector<penumbra::flatland::paint::Stroke> recorded_;
  float zoom_ = 0;  // --zoom, for the canvas the painter started with (0: fit)

  GLFWwindow* window_ = nullptr;
  unsigned texture_ = 0;  // GLuint
  int tex_w_ = 0, tex_h_ = 0;
  std::unique_ptr<Worker> worker_;
  Frame shown_;

  penumbra::flatland::RenderOptions options_;
  std::uint64_t options_version_ = 1;
  std::uint64_t submitted_scene_ = 0, submitted_options_ = 0;
  bool submitted_continuous_ = false;
  Look look_;
  bool continuous_ = false;
  penumbra::Rgb environment_{};
  float environment_intensity_ = 1;

  penumbra::flatland::paint::Brush brush_;
  bool painting_ = false;
  bool undo_down_ = false, save_down_ = false, quit_down_ = false;
  std::string file_ = "painting.json";
  std::string message_;
  std::vector<double> solve_ms_, display_ms_, ui_ms_;
  std::map<std::string, std::vector<double>> stage_ms_;
};

}  // namespace painter
