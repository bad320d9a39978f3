// Two threads: the UI thread owns the window, the canvas and Dear ImGui; the worker renders the
// latest canvas. The UI never waits for the worker, so the window stays responsive when a frame
// is slow.
#include "paint/window.hpp"

#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <type_traits>

#include "core/median.hpp"
#include "core/timer.hpp"
#include "io/image_io.hpp"
#include "io/path_util.hpp"
#include "window_support.hpp"

using namespace penumbra;
using namespace penumbra::flatland;

namespace painter {

static_assert(std::is_same_v<GLuint, unsigned>, "window.hpp holds the texture as unsigned");

namespace {

constexpr int kFailure = 1;
constexpr int kInterrupted = 130;  // SIGINT or SIGTERM: the outputs were still written

}  // namespace

Status painter_memory(int w, int h, const RenderOptions& o) {
  const std::uint64_t need =
      estimate_memory(w, h, o) + 4 * scene_bytes(w, h) +
      std::min<std::uint64_t>(paint::kUndoBytes, paint::kMaxUndoSteps * scene_bytes(w, h));
  if (need <= o.max_memory) return {};
  return Error{"a " + std::to_string(w) + "x" + std::to_string(h) + " canvas with " +
               to_string(o.method) + " needs about " + std::to_string(need >> 20) +
               " MiB with the painter's copies and undo steps, more than the " +
               std::to_string(o.max_memory >> 20) + " MiB limit; paint a smaller grid"};
}

Painter::Painter(const PaintArgs& args, paint::Canvas canvas, std::vector<paint::Stroke> replay)
    : args_(args), canvas_(std::move(canvas)), replay_(std::move(replay)) {
  options_ = args.options;
  zoom_ = args.zoom;
  look_.exposure = args.exposure.value_or(0.0f);
  look_.auto_exposure = !args.exposure;
  look_.materials = !args.plain;
  environment_ = canvas_.scene().environment;
  brush_.intensity = std::min(1.0f, canvas_.emission_scale());
}

float Painter::zoom() const {
  if (zoom_ > 0) return zoom_;
  // About 800 pixels, as tall as the panel needs: whole pixels per cell where that makes at
  // least 700 (a 256^2 canvas at 3), otherwise the fraction that makes 800 (a 512^2 canvas at
  // 1.5625, not 512 pixels beside an 800-pixel panel).
  const int side = std::max(canvas_.width(), canvas_.height());
  const int whole = 800 / side;
  return whole * side >= 700 ? float(whole) : 800.0f / float(side);
}

void Painter::resize_window() {
  const float z = zoom();
  glfwSetWindowSize(window_, int(std::ceil(canvas_.width() * z + kPanelWidth)),
                    int(std::max(std::ceil(canvas_.height() * z), kMinHeight)));
}

void Painter::replace_canvas(paint::Canvas c) {
  canvas_ = std::move(c);
  zoom_ = 0;  // fit the new grid (an explicit zoom could make it larger than the screen)
  environment_ = canvas_.scene().environment;
  environment_intensity_ = 1;
  recorded_.clear();
  brush_.intensity = std::min(brush_.intensity, canvas_.emission_scale());
  resize_window();
}

void Painter::submit() {
  // In continuous mode the canvas goes to the worker every frame; turning it off must reach the
  // worker too, or it would go on solving the same canvas.
  if (canvas_.version() == submitted_scene_ && options_version_ == submitted_options_ &&
      continuous_ == submitted_continuous_ && !continuous_)
    return;
  if (options_version_ != submitted_options_)
    if (Status m = painter_memory(canvas_.width(), canvas_.height(), options_); !m) {
      message_ = m.error().message;  // the worker goes on showing the last accepted settings
      return;
    }
  submitted_scene_ = canvas_.version();
  submitted_options_ = options_version_;
  submitted_continuous_ = continuous_;
  worker_->submit(std::make_shared<const Scene>(canvas_.scene()), submitted_scene_, options_,
                  options_version_, look_, continuous_);
}

void Painter::upload(const Frame& f) {
  if (f.rgb.empty()) return;
  glBindTexture(GL_TEXTURE_2D, texture_);
  // Whole pixels per cell show cells as squares; a fractional zoom would make them uneven.
  const float z = zoom();
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER,
                  z == std::floor(z) ? GL_NEAREST : GL_LINEAR);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  if (f.width != tex_w_ || f.height != tex_h_) {
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, f.width, f.height, 0, GL_RGB, GL_UNSIGNED_BYTE,
                 f.rgb.data());
    tex_w_ = f.width;
    tex_h_ = f.height;
  } else {
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, f.width, f.height, GL_RGB, GL_UNSIGNED_BYTE,
                    f.rgb.data());
  }
}

// Mouse and keys on the canvas (ImGui gets them first when the pointer is over the panel).
void Painter::handle_input() {
  ImGuiIO& io = ImGui::GetIO();
  const float z = zoom();
  const float cx = io.MousePos.x / z, cy = io.MousePos.y / z;
  const bool over_canvas = !io.WantCaptureMouse && io.MousePos.x >= 0 && io.MousePos.y >= 0 &&
                           cx < canvas_.width() + brush_.radius &&
                           cy < canvas_.height() + brush_.radius;
  if (over_canvas && io.MouseWheel != 0)
    brush_.radius =
        std::clamp(brush_.radius * std::pow(1.15f, io.MouseWheel), 0.5f, paint::kMaxBrushRadius);
  if (!painting_ && over_canvas && ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
    if (Status s = canvas_.begin_stroke(brush_, cx, cy); s) {
      painting_ = true;
      recorded_.push_back({brush_, {{cx, cy}}});
    } else {
      message_ = s.error().message;
    }
  } else if (painting_ && ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
    auto& last = recorded_.back().points.back();
    if (cx != last[0] || cy != last[1]) {
      canvas_.extend_stroke(cx, cy);
      recorded_.back().points.push_back({cx, cy});
    }
  } else if (painting_) {
    canvas_.end_stroke();
    painting_ = false;
  }
  // Keys, unless a text field has the keyboard (it takes Ctrl-Z and digits itself).
  const bool typing = io.WantTextInput;
  {  // tools on 1-4
    const int keys[] = {GLFW_KEY_1, GLFW_KEY_2, GLFW_KEY_3, GLFW_KEY_4};
    const paint::Tool tools[] = {paint::Tool::light, paint::Tool::wall, paint::Tool::fog,
                                 paint::Tool::erase};
    for (int k = 0; k < 4; ++k)
      if (glfwGetKey(window_, keys[k]) == GLFW_PRESS && !typing && !painting_)
        brush_.tool = tools[k];
  }
  // Ctrl-Z, Ctrl-S and Ctrl-Q, on the key going down.
  // Every key is read every frame, so that a sticky press is used up in the frame it belongs to.
  auto pressed = [&](int key) { return glfwGetKey(window_, key) == GLFW_PRESS; };
  const bool left_ctrl = pressed(GLFW_KEY_LEFT_CONTROL),
             right_ctrl = pressed(GLFW_KEY_RIGHT_CONTROL);
  const bool key_z = pressed(GLFW_KEY_Z), key_s = pressed(GLFW_KEY_S), key_q = pressed(GLFW_KEY_Q);
  const bool ctrl = !typing && (left_ctrl || right_ctrl);
  const bool z_down = ctrl && key_z;
  if (z_down && !undo_down_ && !painting_ && canvas_.undo() && !recorded_.empty())
    recorded_.pop_back();
  undo_down_ = z_down;
  const bool s_down = ctrl && key_s;
  if (s_down && !save_down_) {
    Status saved = canvas_.save(file_);
    message_ = saved ? "saved " + file_ : saved.error().message;
  }
  save_down_ = s_down;
  const bool q_down = ctrl && key_q;
  if (q_down && !quit_down_) glfwSetWindowShouldClose(window_, GLFW_TRUE);
  quit_down_ = q_down;
}

// The screenshot, the saved painting and the recording, all or nothing.
int Painter::write_outputs(const std::vector<unsigned char>* shot, int shot_w, int shot_h) {
  std::vector<std::string> paths;
  if (shot) paths.push_back(args_.screenshot);
  std::vector<std::string> saved;
  if (!args_.save.empty()) saved = *paint::Canvas::save_paths(args_.save);  // checked up front
  const std::size_t first_saved = paths.size();
  paths.insert(paths.end(), saved.begin(), saved.end());
  if (!args_.record.empty()) paths.push_back(args_.record);
  if (paths.empty()) return 0;
  const paint::StrokeFile record{recorded_, canvas_.width(), canvas_.height()};
  Status s = io::write_all(paths, [&](std::size_t i) -> Expected<io::StagedFile> {
    if (shot && i == 0) return io::stage_png8(paths[0], shot_w, shot_h, *shot);
    if (i >= first_saved && i < first_saved + saved.size())
      return canvas_.stage_save(saved, i - first_saved);
    return io::stage_text(paths[i], paint::strokes_json(record));
  });
  if (!s) {
    std::cerr << "penumbra paint: " << s.error().message << "; nothing written\n";
    return kFailure;
  }
  if (!args_.save.empty())
    std::cout << "penumbra paint: saved " << args_.save
              << "; render it as the window showed it:\n  "
              << painter::render_command(args_.save, options_, look_, shown_.exposure) << "\n";
  return 0;
}

int Painter::run() {
  const float z = zoom();
  // Replays and measurements run as fast as they can; a person gets vsync.
  window_ = window_support::open_window("penumbra paint", "Penumbra painter",
                                        int(std::ceil(canvas_.width() * z + kPanelWidth)),
                                        int(std::max(std::ceil(canvas_.height() * z), kMinHeight)),
                                        args_.replay.empty() && args_.frames == 0, texture_, true);
  if (!window_) return kFailure;

  continuous_ = args_.frames > 0;
  worker_ = std::make_unique<Worker>([] { glfwPostEmptyEvent(); });
  window_support::watch_stop_signals(true);
  int status = 0;
  bool done = false;
  std::vector<unsigned char> shot;
  int shot_w = 0, shot_h = 0;
  while (!done && !glfwWindowShouldClose(window_) && !window_support::stop_requested()) {
    // A replay draws as fast as it can; otherwise the window sleeps until input arrives or the
    // solver posts a new frame (waking twice a second to notice a signal).
    if (replayed_ < replay_.size())
      glfwPollEvents();
    else
      glfwWaitEventsTimeout(0.5);
    Stopwatch frame_watch;  // the window's own work, not the wait
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();

    // A replay paints one stroke per window frame, so it can be watched.
    if (replayed_ < replay_.size()) {
      const std::string where = args_.replay + ": strokes[" + std::to_string(replayed_) + "]";
      if (Status s = canvas_.apply(replay_[replayed_], where); !s) {
        std::cerr << "penumbra paint: " << s.error().message << "\n";
        status = kFailure;
        break;
      }
      recorded_.push_back(replay_[replayed_++]);
    } else {
      handle_input();
    }
    Frame f;
    if (worker_->latest(shown_.serial, f)) {
      upload(f);
      if (!f.error.empty() && f.error != shown_.error)
        std::cerr << "penumbra paint: render refused: " << f.error << "\n";
      if (f.error.empty()) {
        solve_ms_.push_back(f.solve_ms);
        display_ms_.push_back(f.display_ms);
        for (const StageTime& st : f.stages) stage_ms_[st.name].push_back(st.ms);
      }
      shown_ = std::move(f);
    }
    draw_panel();
    submit();  // after the panel, so its changes reach the worker in this pass

    // The picture, then the brush outline over it.
    const float zz = zoom();
    ImDrawList* bg = ImGui::GetBackgroundDrawList();
    if (tex_w_ > 0)
      bg->AddImage((ImTextureID)(std::intptr_t)texture_, ImVec2(0, 0),
                   ImVec2(tex_w_ * zz, tex_h_ * zz));
    const ImVec2 mouse = ImGui::GetIO().MousePos;
    if (replayed_ >= replay_.size() && args_.screenshot.empty() && mouse.x >= 0 &&
        mouse.x < canvas_.width() * zz)
      ImGui::GetForegroundDrawList()->AddCircle(mouse, brush_.radius * zz,
                                                IM_COL32(255, 255, 255, 160), 48);
    ImGui::Render();
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window_, &fw, &fh);
    glViewport(0, 0, fw, fh);
    glClearColor(0.05f, 0.05f, 0.05f, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

    // Scripted runs end once the solver has shown the final canvas, or refused it.
    const bool scripted = !args_.screenshot.empty() || args_.frames > 0;
    const bool current = replayed_ >= replay_.size() && shown_.serial > 0 &&
                         shown_.scene_version == canvas_.version() &&
                         shown_.options_version == options_version_;
    if (scripted && current && !shown_.error.empty()) {
      std::cerr << "penumbra paint: the final canvas could not be rendered; nothing written\n";
      status = kFailure;
      break;
    }
    if (args_.frames > 0 && current && solve_ms_.size() >= std::size_t(args_.frames)) done = true;
    if (!args_.screenshot.empty() && current && args_.frames == 0) done = true;
    if (done && !args_.screenshot.empty())
      shot = window_support::read_window(window_, shot_w, shot_h);
    glfwSwapBuffers(window_);
    ui_ms_.push_back(frame_watch.ms());
  }

  // Outputs first: they need only the canvas, the strokes and the screenshot, not the frame in
  // progress, which may take seconds to finish (RC) and cannot be cut short.
  glfwHideWindow(window_);
  const bool interrupted = window_support::stop_requested();
  if (status == 0)
    status = window_support::scripted_end("penumbra paint", !args_.screenshot.empty(),
                                          !shot.empty(), args_.frames, solve_ms_.size());
  if (status == 0) status = write_outputs(shot.empty() ? nullptr : &shot, shot_w, shot_h);
  if (status == 0 && interrupted) status = kInterrupted;
  window_support::watch_stop_signals(false);
  worker_.reset();
  window_support::close_window(window_, texture_);

  if (args_.stats) {
    std::printf("penumbra paint: %dx%d cells, method %s, %zu solver frames\n", canvas_.width(),
                canvas_.height(), to_string(options_.method), solve_ms_.size());
    std::printf("  solve (render()): median %.2f ms\n", median(solve_ms_));
    for (const StageTime& st : shown_.stages)
      std::printf("    %-22s median %7.2f ms\n", st.name.c_str(), median(stage_ms_[st.name]));
    std::printf("  tone map: median %.2f ms\n", median(display_ms_));
    std::printf("  window: median %.2f ms to draw a frame, %zu frames\n", median(ui_ms_),
                ui_ms_.size());
  }
  return status;
}

}  // namespace painter
