// `penumbra paint`: draw lights, walls and fog with a brush and watch the global illumination.
//
// Two threads: the UI thread owns the window, the canvas and Dear ImGui; the solver thread
// renders the latest canvas from scratch (no temporal reuse, as in the papers) and tone-maps it.
// The UI never waits for the solver, so the window stays responsive when a frame is slow.
#include "paint_cmd.hpp"

#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <imgui_stdlib.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/timer.hpp"
#include "flatland/paint/canvas.hpp"
#include "io/image_io.hpp"
#include "io/path_util.hpp"
#include "parse.hpp"
#include "penumbra/penumbra.hpp"
#include "render_options.hpp"

using namespace penumbra;
using namespace penumbra::flatland;

namespace {

constexpr int kUsage = 2;
constexpr int kFailure = 1;
constexpr int kInterrupted = 130;  // SIGINT or SIGTERM: the outputs were still written
constexpr float kPanelWidth = 340;
constexpr float kMinHeight = 800;  // the panel scrolls when its open sections need more

// ---- the solver thread ----------------------------------------------------------------------

// How the fluence is shown.
struct Look {
  float exposure = 0;     // EV
  bool materials = true;  // walls and fog stay visible where no light reaches them
};

// Unlit walls are black like the dark around them, so a wall painted in the dark would be
// invisible: non-emitting walls and fog get a dim floor of their albedo's colour. Off, the
// window shows exactly what `penumbra render` writes.
void show_materials(const Scene& s, std::vector<unsigned char>& rgb) {
  for (std::size_t i = 0; i < s.cells(); ++i) {
    const float a = s.opacity[i];
    const float* le = &s.emission[3 * i];
    if (a <= 0 || le[0] + le[1] + le[2] > 0) continue;
    const float k = a >= 1 ? 0.3f : 0.3f * std::min(1.0f, 5 * a);
    for (int c = 0; c < 3; ++c) {
      const float floor = 255 * k * (0.25f + 0.75f * s.albedo[3 * i + c]);
      unsigned char& v = rgb[3 * i + c];
      v = std::max(v, static_cast<unsigned char>(floor));
    }
  }
}

// What the solver shows: the display picture of one render, and how long it took.
struct Frame {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;  // 8-bit sRGB, row 0 at the top
  std::vector<StageTime> stages;
  double solve_ms = 0, display_ms = 0;
  std::uint64_t scene_version = 0, options_version = 0;
  std::uint64_t serial = 0;  // counts solved frames
  std::string device;        // what rendered it
  std::string error;         // the render was refused (the picture is the previous one)
};

class Solver {
 public:
  // `on_frame` runs on the solver thread after each frame is published (to wake the UI).
  explicit Solver(std::function<void()> on_frame)
      : on_frame_(std::move(on_frame)), thread_([this] { loop(); }) {}
  // Waits for the frame in progress (a progressive method stops after its current pass).
  ~Solver() {
    {
      std::lock_guard lock(mutex_);
      quit_ = true;
    }
    cancel_.store(true);
    wake_.notify_all();
    thread_.join();
  }

  // Hands the solver a new canvas state; it is rendered once the current frame is done.
  void submit(std::shared_ptr<const Scene> scene, std::uint64_t scene_version,
              const RenderOptions& options, std::uint64_t options_version, const Look& look,
              bool continuous) {
    {
      std::lock_guard lock(mutex_);
      scene_ = std::move(scene);
      scene_version_ = scene_version;
      options_ = options;
      options_version_ = options_version;
      look_ = look;
      continuous_ = continuous;
    }
    wake_.notify_all();
  }

  // The latest frame if it is newer than `serial`.
  bool latest(std::uint64_t serial, Frame& out) {
    std::lock_guard lock(mutex_);
    if (frame_.serial == serial) return false;
    out = frame_;
    return true;
  }

 private:
  void loop() {
    std::uint64_t done_scene = 0, done_options = 0, serial = 0;
    for (;;) {
      std::shared_ptr<const Scene> scene;
      RenderOptions options;
      std::uint64_t scene_version = 0, options_version = 0;
      Look look;
      {
        std::unique_lock lock(mutex_);
        wake_.wait(lock, [&] {
          return quit_ || (scene_ && (continuous_ || scene_version_ != done_scene ||
                                      options_version_ != done_options));
        });
        if (quit_) return;
        scene = scene_;
        options = options_;
        scene_version = scene_version_;
        options_version = options_version_;
        look = look_;
      }
      Frame f;
      f.width = scene->width;
      f.height = scene->height;
      f.scene_version = scene_version;
      f.options_version = options_version;
      f.serial = ++serial;
      options.cancel = &cancel_;
      Stopwatch watch;
      try {  // the library reports errors as values; anything thrown here is shown, not fatal
        Expected<RenderResult> r = renderer_.render(*scene, options);
        f.solve_ms = watch.ms();
        if (r) {
          f.device = r->device;
          f.stages = std::move(r->stages);
          watch.restart();
          f.rgb = display_picture(r->fluence, scene.get(), {look.exposure}).rgb;
          if (look.materials) show_materials(*scene, f.rgb);
          f.display_ms = watch.ms();
        } else {
          f.error = r.error().message;
        }
      } catch (const std::exception& e) {
        f.rgb.clear();
        f.error = std::string("internal error: ") + e.what();
      }
      done_scene = scene_version;
      done_options = options_version;
      {
        std::lock_guard lock(mutex_);
        if (f.rgb.empty()) {  // refused: keep showing the last picture
          f.rgb = std::move(frame_.rgb);
          f.width = frame_.width;
          f.height = frame_.height;
        }
        frame_ = std::move(f);
      }
      on_frame_();
    }
  }

  std::function<void()> on_frame_;
  std::atomic<bool> cancel_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
  std::shared_ptr<const Scene> scene_;
  std::uint64_t scene_version_ = 0, options_version_ = 0;
  RenderOptions options_;
  Look look_;
  bool continuous_ = false, quit_ = false;
  Frame frame_;
  Renderer renderer_;   // keeps its buffers from frame to frame (used by the solver thread only)
  std::thread thread_;  // last: starts once the members above exist
};

// ---- the window -----------------------------------------------------------------------------

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// GLFW reports errors through a callback, possibly on the solver thread (glfwPostEmptyEvent).
std::mutex glfw_error_mutex;
std::string glfw_error;

extern "C" void on_glfw_error(int, const char* text) {
  std::lock_guard lock(glfw_error_mutex);
  glfw_error = text ? text : "unknown error";
}

std::string last_glfw_error() {
  std::lock_guard lock(glfw_error_mutex);
  return glfw_error;
}

// SIGINT and SIGTERM end the session as closing the window does (outputs are still written).
std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) {
  g_stop.store(true);
}

// The method's working memory plus the painter's copies of the canvas (the canvas, a stroke's
// starting cells, the solver's two) and its undo steps, against the method's memory limit.
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

class Painter {
 public:
  Painter(const PaintArgs& args, paint::Canvas canvas, std::vector<paint::Stroke> replay)
      : args_(args), canvas_(std::move(canvas)), replay_(std::move(replay)) {
    options_ = args.options;
    zoom_ = args.zoom;
    look_.exposure = args.exposure;
    look_.materials = !args.plain;
    environment_ = canvas_.scene().environment;
    brush_.intensity = std::min(1.0f, canvas_.emission_scale());
  }

  int run();

 private:
  float zoom() const;
  void resize_window();
  void handle_input();
  void draw_panel();
  void submit();
  void upload(const Frame& f);
  std::vector<unsigned char> read_window(int& w, int& h);
  int write_outputs(const std::vector<unsigned char>* shot, int shot_w, int shot_h);
  void replace_canvas(paint::Canvas c);

  const PaintArgs& args_;
  paint::Canvas canvas_;
  std::vector<paint::Stroke> replay_;
  std::size_t replayed_ = 0;
  std::vector<paint::Stroke> recorded_;
  float zoom_ = 0;  // --zoom, for the canvas the painter started with (0: fit)

  GLFWwindow* window_ = nullptr;
  GLuint texture_ = 0;
  int tex_w_ = 0, tex_h_ = 0;
  std::unique_ptr<Solver> solver_;
  Frame shown_;

  RenderOptions options_;
  std::uint64_t options_version_ = 1;
  std::uint64_t submitted_scene_ = 0, submitted_options_ = 0;
  bool submitted_continuous_ = false;
  Look look_;
  bool continuous_ = false;
  Rgb environment_{};
  float environment_intensity_ = 1;

  paint::Brush brush_;
  bool painting_ = false;
  bool undo_down_ = false, save_down_ = false, quit_down_ = false;
  std::string file_ = "painting.json";
  std::string message_;
  std::vector<double> solve_ms_, display_ms_, ui_ms_;
  std::map<std::string, std::vector<double>> stage_ms_;
};

float Painter::zoom() const {
  if (zoom_ > 0) return zoom_;
  const int side = std::max(canvas_.width(), canvas_.height());
  return side <= 800 ? float(std::max(1, 800 / side)) : 800.0f / float(side);
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
  // In continuous mode the canvas goes to the solver every frame; turning it off must reach the
  // solver too, or it would go on solving the same canvas.
  if (canvas_.version() == submitted_scene_ && options_version_ == submitted_options_ &&
      continuous_ == submitted_continuous_ && !continuous_)
    return;
  if (options_version_ != submitted_options_)
    if (Status m = painter_memory(canvas_.width(), canvas_.height(), options_); !m) {
      message_ = m.error().message;  // the solver goes on showing the last accepted settings
      return;
    }
  submitted_scene_ = canvas_.version();
  submitted_options_ = options_version_;
  submitted_continuous_ = continuous_;
  solver_->submit(std::make_shared<const Scene>(canvas_.scene()), submitted_scene_, options_,
                  options_version_, look_, continuous_);
}

void Painter::upload(const Frame& f) {
  if (f.rgb.empty()) return;
  glBindTexture(GL_TEXTURE_2D, texture_);
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

void Painter::draw_panel() {
  const float z = zoom();
  ImGui::SetNextWindowPos(ImVec2(canvas_.width() * z, 0));
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, ImGui::GetIO().DisplaySize.y));
  ImGui::Begin("Penumbra painter", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::Text("grid %d x %d cells, zoom %.2f", canvas_.width(), canvas_.height(), z);

  // The frame: per stage, as the solver measured it.
  if (ImGui::CollapsingHeader("Frame", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Text("method %s on %s, frame %llu", to_string(options_.method), shown_.device.c_str(),
                (unsigned long long)shown_.serial);
    ImGui::Text("solve %.1f ms (%.0f fps), display %.1f ms", shown_.solve_ms,
                shown_.solve_ms > 0 ? 1000.0 / shown_.solve_ms : 0.0, shown_.display_ms);
    for (const StageTime& s : shown_.stages) ImGui::Text("  %-22s %7.2f ms", s.name.c_str(), s.ms);
    ImGui::Text("window: %.1f ms to draw a frame", ui_ms_.empty() ? 0.0 : ui_ms_.back());
    if (!shown_.error.empty()) ImGui::TextWrapped("render refused: %s", shown_.error.c_str());
  }

  if (ImGui::CollapsingHeader("Brush", ImGuiTreeNodeFlags_DefaultOpen)) {
    int tool = int(brush_.tool);
    ImGui::RadioButton("light", &tool, int(paint::Tool::light));
    ImGui::SameLine();
    ImGui::RadioButton("wall", &tool, int(paint::Tool::wall));
    ImGui::SameLine();
    ImGui::RadioButton("fog", &tool, int(paint::Tool::fog));
    ImGui::SameLine();
    ImGui::RadioButton("eraser", &tool, int(paint::Tool::erase));
    brush_.tool = paint::Tool(tool);
    if (brush_.tool != paint::Tool::erase)
      ImGui::ColorEdit3(brush_.tool == paint::Tool::light ? "colour" : "albedo", &brush_.color.r);
    if (brush_.tool == paint::Tool::light)
      ImGui::SliderFloat("intensity", &brush_.intensity, 0.01f, canvas_.emission_scale(), "%.2f",
                         ImGuiSliderFlags_Logarithmic);
    if (brush_.tool == paint::Tool::fog)
      ImGui::SliderFloat("opacity", &brush_.opacity, 0.001f, 0.99f, "%.3f",
                         ImGuiSliderFlags_Logarithmic);
    ImGui::SliderFloat("radius", &brush_.radius, 0.5f, paint::kMaxBrushRadius, "%.1f cells",
                       ImGuiSliderFlags_Logarithmic);
    ImGui::TextDisabled("keys 1-4: tool; wheel: radius; Ctrl-Z: undo; Ctrl-Q: quit");
    if (ImGui::Button("Undo") && canvas_.undo() && !recorded_.empty()) recorded_.pop_back();
    ImGui::SameLine();
    if (ImGui::Button("Clear")) {
      canvas_.clear();
      // A stroke file has no "clear": record an eraser covering every cell.
      const float w = float(canvas_.width()), h = float(canvas_.height());
      paint::Brush e;
      e.tool = paint::Tool::erase;
      e.radius = std::min(std::hypot(w, h), paint::kMaxBrushRadius);
      paint::Stroke s{e, {}};
      for (float y = 0; y < h + e.radius; y += e.radius)
        for (float x = 0; x < w + e.radius; x += e.radius) s.points.push_back({x, y});
      recorded_.push_back(std::move(s));
    }
    ImGui::SameLine();
    ImGui::Text("%zu undo steps", canvas_.undo_steps());
  }

  if (ImGui::CollapsingHeader("Environment", ImGuiTreeNodeFlags_DefaultOpen)) {
    bool changed = ImGui::ColorEdit3("colour##env", &environment_.r);
    changed |= ImGui::SliderFloat("radiance", &environment_intensity_, 0.0f, 4.0f, "%.3f",
                                  ImGuiSliderFlags_Logarithmic);
    if (changed)
      canvas_.set_environment({environment_.r * environment_intensity_,
                               environment_.g * environment_intensity_,
                               environment_.b * environment_intensity_});
  }

  if (ImGui::CollapsingHeader("Method", ImGuiTreeNodeFlags_DefaultOpen)) {
    bool changed = false;
    int m = int(options_.method);
    const char* names[] = {to_string(Method(0)), to_string(Method(1)), to_string(Method(2))};
    if (ImGui::Combo("method", &m, names, 3)) options_.method = Method(m), changed = true;
    int device = int(options_.device);
    const char* devices[] = {to_string(Device(0)), to_string(Device(1)), to_string(Device(2))};
    if (ImGui::Combo("device", &device, devices, 3))
      options_.device = Device(device), changed = true;
    changed |= ImGui::SliderInt("bounces", &options_.bounces, 1, 8);
    changed |= ImGui::SliderInt("threads", &options_.threads, 0,
                                int(std::max(1u, std::thread::hardware_concurrency())),
                                options_.threads == 0 ? "all" : "%d");
    if (options_.method == Method::hrc) {
      bool f16 = options_.hrc.storage == Storage::f16;
      if (ImGui::Checkbox("f16 storage", &f16))
        options_.hrc.storage = f16 ? Storage::f16 : Storage::f32, changed = true;
      changed |= ImGui::Checkbox("cross blur", &options_.hrc.cross_blur);
      changed |= ImGui::Checkbox("near segment", &options_.hrc.near_segment);
    } else if (options_.method == Method::rc) {
      RcOptions& rc = options_.rc;
      changed |= ImGui::SliderInt("probe spacing", &rc.probe_spacing, 1, 16);
      changed |= ImGui::SliderInt("directions Q0", &rc.directions, 1, 16);
      changed |= ImGui::SliderFloat("interval t0", &rc.interval, 0.5f, 64.0f, "%.1f",
                                    ImGuiSliderFlags_Logarithmic);
      int fix = int(rc.fix);
      const char* fixes[] = {"bilinear fix", "vanilla", "nearest"};
      if (ImGui::Combo("merge", &fix, fixes, 3)) rc.fix = MergeFix(fix), changed = true;
    } else {
      changed |= ImGui::SliderInt("spp", &options_.pt.spp, 1, 256);
      changed |= ImGui::Checkbox("next event estimation", &options_.pt.nee);
    }
    changed |= ImGui::SliderFloat("exposure (EV)", &look_.exposure, -8.0f, 8.0f, "%.1f");
    changed |= ImGui::Checkbox("show walls and fog", &look_.materials);
    ImGui::Checkbox("solve every frame", &continuous_);
    if (changed) ++options_version_;
  }

  if (ImGui::CollapsingHeader("File", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::InputText("scene file", &file_);
    if (ImGui::Button("Save")) {
      Status s = canvas_.save(file_);
      message_ = s ? "saved " + file_ : s.error().message;
    }
    ImGui::SameLine();
    if (ImGui::Button("Load")) {
      Expected<SceneDesc> desc = load_scene(file_);
      Expected<paint::Canvas> c =
          desc ? paint::Canvas::from_scene(*desc,
                                           args_.emission_scale_given ? args_.emission_scale : 0)
               : Expected<paint::Canvas>(desc.error());
      if (c)
        if (Status m = painter_memory(c->width(), c->height(), options_); !m) c = m.error();
      if (c) {
        replace_canvas(std::move(*c));
        message_ = "loaded " + file_;
      } else {
        message_ = c.error().message;
      }
    }
    ImGui::TextDisabled("emission scale %g", canvas_.emission_scale());
    if (!message_.empty()) ImGui::TextWrapped("%s", message_.c_str());
  }
  ImGui::End();
}

// The window's back buffer as 8-bit RGB, row 0 at the top.
std::vector<unsigned char> Painter::read_window(int& w, int& h) {
  glfwGetFramebufferSize(window_, &w, &h);
  std::vector<unsigned char> rgb(std::size_t(w) * h * 3), flipped(rgb.size());
  glFinish();
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
  const std::size_t row = std::size_t(w) * 3;
  for (int y = 0; y < h; ++y)  // OpenGL's rows start at the bottom
    std::copy_n(&rgb[std::size_t(h - 1 - y) * row], row, &flipped[std::size_t(y) * row]);
  return flipped;
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
  return 0;
}

int Painter::run() {
  glfwSetErrorCallback(on_glfw_error);
  if (!glfwInit()) {
    std::cerr << "penumbra paint: no display: cannot open a window (" << last_glfw_error()
              << "); set DISPLAY, or run under Xvfb for scripted use\n";
    return kFailure;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  const float z = zoom();
  window_ = glfwCreateWindow(int(std::ceil(canvas_.width() * z + kPanelWidth)),
                             int(std::max(std::ceil(canvas_.height() * z), kMinHeight)),
                             "Penumbra painter", nullptr, nullptr);
  if (!window_) {
    std::cerr << "penumbra paint: cannot create an OpenGL 3.0 window: " << last_glfw_error()
              << "\n";
    glfwTerminate();
    return kFailure;
  }
  glfwMakeContextCurrent(window_);
  // Shortcuts are polled once a frame: sticky keys keep a tap that is over before the poll.
  glfwSetInputMode(window_, GLFW_STICKY_KEYS, GLFW_TRUE);
  // Replays and measurements run as fast as they can; a person gets vsync.
  glfwSwapInterval(args_.replay.empty() && args_.frames == 0 ? 1 : 0);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the working directory
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 130");
  glGenTextures(1, &texture_);
  glBindTexture(GL_TEXTURE_2D, texture_);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);

  continuous_ = args_.frames > 0;
  solver_ = std::make_unique<Solver>([] { glfwPostEmptyEvent(); });
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  int status = 0;
  bool done = false;
  std::vector<unsigned char> shot;
  int shot_w = 0, shot_h = 0;
  while (!done && !glfwWindowShouldClose(window_) && !g_stop.load()) {
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
    if (solver_->latest(shown_.serial, f)) {
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
    submit();  // after the panel, so its changes reach the solver in this pass

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
    if (done && !args_.screenshot.empty()) shot = read_window(shot_w, shot_h);
    glfwSwapBuffers(window_);
    ui_ms_.push_back(frame_watch.ms());
  }

  // Outputs first: they need only the canvas, the strokes and the screenshot, not the frame in
  // progress, which may take seconds to finish (RC) and cannot be cut short.
  glfwHideWindow(window_);
  const bool interrupted = g_stop.load();
  if (status == 0 && !args_.screenshot.empty() && shot.empty()) {
    std::cerr << "penumbra paint: " << (interrupted ? "interrupted" : "the window was closed")
              << " before the final frame; nothing written\n";
    status = kFailure;
  }
  if (status == 0 && args_.frames > 0 && solve_ms_.size() < std::size_t(args_.frames)) {
    std::cerr << "penumbra paint: " << (interrupted ? "interrupted" : "the window was closed")
              << " after " << solve_ms_.size() << " of " << args_.frames
              << " frames; nothing written\n";
    status = kFailure;
  }
  if (status == 0) status = write_outputs(shot.empty() ? nullptr : &shot, shot_w, shot_h);
  if (status == 0 && interrupted) status = kInterrupted;
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  solver_.reset();
  glDeleteTextures(1, &texture_);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window_);
  glfwTerminate();

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

}  // namespace

bool PaintCommand::parsed() const {
  return app->parsed();
}

std::unique_ptr<PaintCommand> add_paint_command(CLI::App& app) {
  auto cmd = std::make_unique<PaintCommand>();
  PaintArgs& a = cmd->args;
  cmd->app = app.add_subcommand("paint", "Paint lights, walls and fog; see the light at once");
  CLI::App* c = cmd->app;
  c->add_option("scene", a.scene, "Scene file to start from (JSON, format 1)");
  c->add_option("--size", a.size, "Grid of a blank canvas, WxH cells")->capture_default_str();
  // The render options the window can change too, in two calls to keep the help in its order;
  // paint says its own help and allows fewer bounces.
  RenderOptionSet first, second;
  first.method = first.device = true;
  first.methods = {Method::hrc, Method::rc, Method::pt};
  first.method_help = "Method (switchable in the window)";
  first.device_help = "Where the solver runs: cpu, gpu (Vulkan; HRC, one bounce, f32), auto";
  second.storage = second.bounces = second.threads = true;
  second.max_bounces = 8;
  second.bounces_help = "Diffuse bounces";
  second.threads_help = "Solver threads (0: all cores)";
  add_render_options(c, a.options, a.flags, first);
  c->add_option("--replay", a.replay, "Stroke file to paint, one stroke per window frame");
  c->add_option("--screenshot", a.screenshot,
                "Save the window as PNG once the solver shows the final canvas, then exit");
  c->add_option("--record", a.record, "Write the strokes painted to this file at exit");
  c->add_option("--save", a.save,
                "Write the painting as a scene file (JSON + 16-bit PNG layers) at exit");
  c->add_option("--zoom", a.zoom, "Window pixels per cell (0: fit about 800 pixels)")
      ->check(CLI::Range(0.0f, 64.0f))
      ->capture_default_str();
  c->add_option("--emission-scale", a.emission_scale,
                "Brightest radiance the canvas holds (the saved emission_scale); a scene's "
                "brightest cell raises it")
      ->check(CLI::Range(1e-3f, 1e9f))
      ->each([&a](const std::string&) { a.emission_scale_given = true; })
      ->capture_default_str();
  add_render_options(c, a.options, a.flags, second);
  c->add_option("--exposure", a.exposure, "Display exposure in EV")->capture_default_str();
  c->add_option("--frames", a.frames,
                "Solve continuously and exit after this many solver frames (measurement)")
      ->check(CLI::Range(0, 1 << 20));
  c->add_flag("--plain", a.plain,
              "Show the fluence exactly as `penumbra render` writes it (no dim floor for unlit "
              "walls and fog)");
  c->add_flag("--stats", a.stats, "At exit, print the median solve and window frame times");
  return cmd;
}

int run_paint(const PaintArgs& args) {
  PaintArgs a = args;  // the painter starts from the finished options
  finish_render_options(a.options, a.flags);
  if (!std::isfinite(a.exposure)) {
    std::cerr << "penumbra paint: --exposure: expected a finite number of EV\n";
    return kUsage;
  }
  // Everything the files say is checked before a window opens.
  Expected<paint::Canvas> canvas = Error{""};
  if (a.scene.empty()) {
    int w = 0, h = 0;
    if (!parse_grid_size(a.size, w, h)) {
      std::cerr << "penumbra paint: --size: expected WxH such as 256x256, found '" << a.size
                << "'\n";
      return kUsage;
    }
    canvas = paint::Canvas::blank(w, h, a.emission_scale);
  } else {
    Expected<SceneDesc> desc = load_scene(a.scene);
    canvas = desc ? paint::Canvas::from_scene(*desc, a.emission_scale_given ? a.emission_scale : 0)
                  : Expected<paint::Canvas>(desc.error());
  }
  if (!canvas) {
    std::cerr << "penumbra paint: " << canvas.error().message << "\n";
    return kFailure;
  }
  // Memory: the method's, plus the painter's copies of the canvas (the canvas, the stroke's
  // starting cells, the solver's two) and its undo steps.
  const RenderOptions& probe = a.options;
  if (Status s = check_options(canvas->width(), canvas->height(), probe); !s) {
    std::cerr << "penumbra paint: " << s.error().message << "\n";
    return kUsage;
  }
  const int w = canvas->width(), h = canvas->height();
  if (Status s = check_memory(w, h, probe, false); !s) {
    std::cerr << "penumbra paint: " << s.error().message << "\n";
    return kFailure;
  }
  if (Status s = painter_memory(w, h, probe); !s) {
    std::cerr << "penumbra paint: " << s.error().message << "\n";
    return kFailure;
  }
  std::vector<paint::Stroke> strokes;
  if (!a.replay.empty()) {
    Expected<paint::StrokeFile> r = paint::load_strokes(a.replay);
    if (!r) {
      std::cerr << "penumbra paint: " << r.error().message << "\n";
      return kFailure;
    }
    for (std::size_t i = 0; i < r->strokes.size(); ++i)
      if (Status s =
              canvas->check(r->strokes[i].brush, a.replay + ": strokes[" + std::to_string(i) + "]");
          !s) {
        std::cerr << "penumbra paint: " << s.error().message << "\n";
        return kFailure;
      }
    if (r->width > 0 && (r->width != w || r->height != h))
      std::cerr << "penumbra paint: warning: " << a.replay << " was painted on a " << r->width
                << "x" << r->height << " grid; replaying it on " << w << "x" << h << "\n";
    strokes = std::move(r->strokes);
  }

  // Outputs: names checked, places writable, no two the same file.
  if (!a.screenshot.empty() && io::lowercase_extension(a.screenshot) != ".png") {
    std::cerr << "penumbra paint: --screenshot: " << a.screenshot << ": expected a .png name\n";
    return kUsage;
  }
  std::vector<std::pair<std::string, std::string>> outputs;  // option, path
  if (!a.screenshot.empty()) outputs.push_back({"--screenshot", a.screenshot});
  if (!a.save.empty()) {
    Expected<std::vector<std::string>> saved = paint::Canvas::save_paths(a.save);
    if (!saved) {
      std::cerr << "penumbra paint: --save: " << saved.error().message << "\n";
      return kUsage;
    }
    for (const std::string& p : *saved) outputs.push_back({"--save", p});
  }
  if (!a.record.empty()) outputs.push_back({"--record", a.record});
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    if (Status s = check_output(outputs[i].second); !s) {
      std::cerr << "penumbra paint: " << outputs[i].first << ": " << s.error().message << "\n";
      return kFailure;
    }
    auto canonical = [](const std::string& p) {
      std::error_code ec;
      std::filesystem::path c = std::filesystem::weakly_canonical(p, ec);
      if (ec) c = std::filesystem::absolute(p, ec).lexically_normal();
      return ec ? std::filesystem::path(p) : c;
    };
    const std::filesystem::path pi = canonical(outputs[i].second);
    for (std::size_t j = 0; j < i; ++j)
      if (pi == canonical(outputs[j].second)) {
        std::cerr << "penumbra paint: " << outputs[j].first << " and " << outputs[i].first
                  << " would both write " << outputs[i].second << "\n";
        return kUsage;
      }
  }
  try {
    Painter painter(a, std::move(*canvas), std::move(strokes));
    return painter.run();
  } catch (const std::exception& e) {
    std::cerr << "penumbra paint: " << e.what() << "\n";
    return kFailure;
  }
}
