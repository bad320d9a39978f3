// Two threads: the UI thread owns the window, the camera and Dear ImGui; the worker renders the
// latest view. The UI never waits for the worker, so flying stays smooth when a frame is slow.
#include "view/viewer.hpp"

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
#include <cstring>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <optional>
#include <type_traits>

#include "core/median.hpp"
#include "core/timer.hpp"
#include "io/image_io.hpp"
#include "view/save.hpp"
#include "window_support.hpp"

using penumbra::Status;
using penumbra::Vec3;
namespace sl = penumbra::spaceland;

namespace viewer {

static_assert(std::is_same_v<GLuint, unsigned>, "viewer.hpp holds the texture as unsigned");

namespace {

constexpr int kFailure = 1;
constexpr int kInterrupted = 130;
constexpr float kDegrees = 3.14159265358979323846f / 180;
// A still camera gets its full-resolution frame after this long without moving.
constexpr double kStillSeconds = 0.25;

// The scene format's reading of a direction: normalised in double (scene_json.cpp), so that a
// saved sun reads back as the same floats.
Vec3 as_loaded(Vec3 v) {
  const double len = std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
  return {float(v.x / len), float(v.y / len), float(v.z / len)};
}

bool same(const Fly& a, const Fly& b) {
  return a.position.x == b.position.x && a.position.y == b.position.y &&
         a.position.z == b.position.z && a.yaw == b.yaw && a.pitch == b.pitch;
}

}  // namespace

Viewer::Viewer(const ViewArgs& args, sl::Scene scene, nlohmann::json doc, Settings settings,
               Replay replay)
    : args_(args),
      scene_(std::move(scene)),
      doc_(std::move(doc)),
      settings_(std::move(settings)),
      replay_(std::move(replay)) {
  fly_ = Fly::from(scene_.camera);
  start_fly_ = recorded_fly_ = fly_;
  recorded_settings_ = settings_;
  const Vec3 d = scene_.camera.look_at - scene_.camera.position;
  speed_ = std::max(0.5f * std::sqrt(dot(d, d)), 1e-3f);
  save_path_ = args_.save.empty() ? "view.json" : args_.save;
  if (scene_.has_sun && !settings_.sun_moved) {  // the panel starts at the scene's sun
    const Vec3 d = scene_.sun.direction, side = cross(fly_.reference, fly_.up);
    settings_.sun_elevation = std::asin(std::clamp(dot(d, fly_.up), -1.0f, 1.0f)) / kDegrees;
    settings_.sun_azimuth = std::atan2(dot(d, side), dot(d, fly_.reference)) / kDegrees;
    recorded_settings_ = settings_;
  }
}

Vec3 Viewer::sun_direction() const {
  const Vec3 side = cross(fly_.reference, fly_.up);
  const float a = settings_.sun_azimuth * kDegrees, e = settings_.sun_elevation * kDegrees;
  return (fly_.reference * std::cos(a) + side * std::sin(a)) * std::cos(e) + fly_.up * std::sin(e);
}

sl::Camera Viewer::camera() const {
  return fly_.camera(scene_.camera);
}

Job Viewer::make_job() {
  const int w = scene_.camera.width, h = scene_.camera.height;
  const bool scripted_end = replayed_ >= replay_.events.size() && waiting_ == 0 &&
                            (!args_.screenshot.empty() || args_.frames > 0);
  const bool still =
      args_.frames == 0 && args_.still_full && (still_s_ >= kStillSeconds || scripted_end);
  bool automatic = false;
  float s = settings_.scale;
  if (s == 0) {
    automatic = !still;
    s = still ? 1.0f : auto_scale_;
  }
  sl::Camera c = camera();
  c.width = std::max(8, int(std::lround(w * s)));
  c.height = std::max(8, int(std::lround(h * s)));
  const Vec3 sun =
      scene_.has_sun && settings_.sun_moved ? as_loaded(sun_direction()) : scene_.sun.direction;
  // A new view (and a copy of the scene for the worker) only when something the frame depends
  // on changed.
  // The exposure alone only tone-maps the last image again (Job::image stays).
  nlohmann::json changed_settings = diff_settings(settings_, job_settings_, true);
  if (changed_settings.is_object()) changed_settings.erase("exposure");
  const bool image_changed =
      !job_.scene || job_.automatic != automatic || c.width != job_.scene->camera.width ||
      c.height != job_.scene->camera.height ||
      std::memcmp(&c.position, &job_.scene->camera.position, sizeof(Vec3)) != 0 ||
      std::memcmp(&c.look_at, &job_.scene->camera.look_at, sizeof(Vec3)) != 0 ||
      std::memcmp(&sun, &job_.scene->sun.direction, sizeof(Vec3)) != 0 ||
      !(changed_settings.is_null() || changed_settings.empty());
  if (!image_changed && settings_.exposure == job_.exposure) return job_;
  Job j;
  if (!image_changed) {  // the same scene copies, the image tone-mapped again
    j = job_;
    j.exposure = settings_.exposure;
    j.version = ++version_;
    job_settings_ = settings_;
    current_frames_ = 0;
    return j;
  }
  j.image = ++image_version_;
  j.automatic = automatic;
  j.scale = s;
  auto scene = std::make_shared<sl::Scene>(scene_);
  scene->camera = c;
  scene->sun.direction = sun;
  if (settings_.guided && (c.width != w || c.height != h)) {
    auto view = std::make_shared<sl::Scene>(*scene);
    view->camera.width = w;
    view->camera.height = h;
    j.view = std::move(view);
  }
  j.scene = std::move(scene);
  j.options = settings_.options;
  j.options.surface.atlas = args_.atlas;
  if (j.options.method == sl::Method::ssrc || j.options.method == sl::Method::spwi)
    j.options.temporal.frames = settings_.temporal;
  if (j.options.method == sl::Method::grid) j.options.temporal.grid_slabs = settings_.grid_slabs;
  j.exposure = settings_.exposure;
  j.version = ++version_;
  job_settings_ = settings_;
  current_frames_ = 0;
  return j;
}

void Viewer::update_scale(const Frame& f) {
  // Frames of an older view count (while flying, every frame is of an older view), as long as
  // they were rendered at the scale now in use.
  if (!f.automatic || !f.error.empty() || f.retoned || f.scale != auto_scale_) return;
  // The method's part grows with the internal pixels; the upscaling (a G-buffer at the view's
  // size) and the tone mapping do not. The method gets what they leave of the target, at least
  // a quarter of it, and the scale moves by the square root of how far off its part was.
  const double fixed = f.upscale_ms + f.display_ms;
  const double method = std::max(f.solve_ms - f.upscale_ms, 0.05);
  const double budget = std::max(settings_.target_ms - fixed, 0.25 * settings_.target_ms);
  const double ratio = budget / method;
  if (ratio > 1.3 || ratio < 0.85)
    auto_scale_ =
        std::clamp(float(auto_scale_ * std::clamp(std::sqrt(ratio), 0.5, 2.0)), 1.0f / 16, 1.0f);
}

void Viewer::upload(const Frame& f) {
  if (f.rgb.empty()) return;
  glBindTexture(GL_TEXTURE_2D, texture_);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  // The view's size shows pixels as they are; a smaller internal image is filtered up.
  const bool exact = f.width == scene_.camera.width && f.height == scene_.camera.height;
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, exact ? GL_NEAREST : GL_LINEAR);
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

void Viewer::handle_input(double dt) {
  ImGuiIO& io = ImGui::GetIO();
  const float w = float(scene_.camera.width), h = float(scene_.camera.height);
  const bool over_view = !io.WantCaptureMouse && io.MousePos.x >= 0 && io.MousePos.y >= 0 &&
                         io.MousePos.x < w && io.MousePos.y < h;
  const Fly before = fly_;
  // Looking: drag with either button over the view.
  const bool down =
      ImGui::IsMouseDown(ImGuiMouseButton_Left) || ImGui::IsMouseDown(ImGuiMouseButton_Right);
  if (!looking_ && down && over_view) {
    looking_ = true;
  } else if (looking_ && down) {
    fly_.turn(0.2f * io.MouseDelta.x, -0.2f * io.MouseDelta.y);
  } else {
    looking_ = false;
  }
  if (over_view && io.MouseWheel != 0)
    speed_ = std::clamp(speed_ * std::pow(1.25f, io.MouseWheel), 1e-6f, 1e9f);
  const bool typing = io.WantTextInput;
  auto key = [&](int k) { return !typing && glfwGetKey(window_, k) == GLFW_PRESS; };
  const bool ctrl = key(GLFW_KEY_LEFT_CONTROL) || key(GLFW_KEY_RIGHT_CONTROL);
  moving_ = false;
  if (!ctrl) {
    Vec3 m{float(key(GLFW_KEY_D)) - float(key(GLFW_KEY_A)),
           float(key(GLFW_KEY_E)) - float(key(GLFW_KEY_Q)),
           float(key(GLFW_KEY_W)) - float(key(GLFW_KEY_S))};
    const float fast = key(GLFW_KEY_LEFT_SHIFT) || key(GLFW_KEY_RIGHT_SHIFT) ? 4.0f : 1.0f;
    moving_ = m.x != 0 || m.y != 0 || m.z != 0;
    if (moving_) fly_.move(m * float(speed_ * fast * dt));
  }
  const bool q_down = ctrl && key(GLFW_KEY_Q), s_down = ctrl && key(GLFW_KEY_S);
  if (q_down && !quit_down_) glfwSetWindowShouldClose(window_, GLFW_TRUE);
  if (s_down && !save_down_) save_view_now(save_path_);
  quit_down_ = q_down;
  save_down_ = s_down;
  still_s_ = same(before, fly_) ? still_s_ + dt : 0;
}

bool Viewer::apply_event(const Event& e) {
  const std::string where = args_.replay + ": events[" + std::to_string(replayed_) + "]";
  switch (e.kind) {
    case Event::Kind::camera:
      fly_ = start_fly_;
      fly_.position = e.position;
      fly_.yaw = 0;
      fly_.pitch = start_fly_.pitch;
      fly_.turn(e.yaw, 0);
      fly_.pitch = e.pitch;
      break;
    case Event::Kind::move:
      fly_.move(e.by);
      fly_.turn(e.turn_yaw, e.turn_pitch);
      break;
    case Event::Kind::set:
      if (Status s = apply_set(e.set, where + ".set", settings_, scene_.has_sun); !s) {
        std::cerr << "penumbra view: " << s.error().message << "\n";
        return false;
      }
      break;
    case Event::Kind::wait:
      waiting_ = e.frames;
      break;
  }
  return true;
}

void Viewer::record_camera() {
  if (args_.record.empty()) return;
  if (nlohmann::json d = diff_settings(settings_, recorded_settings_, scene_.has_sun);
      !d.is_null()) {
    Event e;
    e.kind = Event::Kind::set;
    e.set = d;
    recorded_.events.push_back(e);
    recorded_settings_ = settings_;
  }
  if (!same(fly_, recorded_fly_)) {
    Event e;
    e.kind = Event::Kind::camera;
    e.position = fly_.position;
    e.yaw = fly_.yaw;
    e.pitch = fly_.pitch;
    recorded_.events.push_back(e);
    recorded_fly_ = fly_;
  }
}

void Viewer::save_view_now(const std::string& path) {
  std::error_code ec1, ec2;
  if (std::filesystem::weakly_canonical(path, ec1) ==
      std::filesystem::weakly_canonical(args_.scene, ec2)) {
    message_ = path + " is the scene file: save the view under another name";
    std::cerr << "penumbra view: " << message_ << "\n";
    return;
  }
  std::optional<Vec3> sun;
  if (scene_.has_sun && settings_.sun_moved) sun = sun_direction();
  const nlohmann::json saved = saved_view(doc_, args_.scene, path, camera(), sun);
  if (Status s = save_view(saved, path); !s) {
    message_ = s.error().message;
    std::cerr << "penumbra view: " << message_ << "\n";
    return;
  }
  message_ = "saved " + path;
  std::cout << "penumbra view: saved " << path << "; render this view at full resolution:\n  "
            << render_command(path, settings_, args_.atlas, args_.max_memory) << "\n"
            << std::flush;
}

int Viewer::write_outputs(const std::vector<unsigned char>* shot, int w, int h) {
  std::vector<std::string> paths;
  if (shot) paths.push_back(args_.screenshot);
  if (!args_.record.empty()) paths.push_back(args_.record);
  if (!args_.save.empty()) paths.push_back(args_.save);
  if (paths.empty()) return 0;
  std::optional<Vec3> sun;
  if (scene_.has_sun && settings_.sun_moved) sun = sun_direction();
  const std::string view =
      args_.save.empty() ? ""
                         : saved_view(doc_, args_.scene, args_.save, camera(), sun).dump(2) + "\n";
  Status s = penumbra::io::write_all(
      paths, [&](std::size_t i) -> penumbra::Expected<penumbra::io::StagedFile> {
        if (shot && i == 0) return penumbra::io::stage_png8(paths[0], w, h, *shot);
        if (paths[i] == args_.record)
          return penumbra::io::stage_text(paths[i], replay_json(recorded_));
        return penumbra::io::stage_text(paths[i], view);
      });
  if (!s) {
    std::cerr << "penumbra view: " << s.error().message << "; nothing written\n";
    return kFailure;
  }
  if (!args_.save.empty())
    std::cout << "penumbra view: saved " << args_.save
              << "; render this view at full resolution:\n  "
              << render_command(args_.save, settings_, args_.atlas, args_.max_memory) << "\n";
  return 0;
}

int Viewer::run() {
  const int w = scene_.camera.width, h = scene_.camera.height;
  const bool scripted = !args_.screenshot.empty() || args_.frames > 0;
  // Replays and measurements run as fast as they can; a person gets vsync.
  window_ = window_support::open_window("penumbra view", "Penumbra viewer", int(w + kPanelWidth),
                                        int(std::max(float(h), kMinHeight)),
                                        !scripted && args_.replay.empty(), texture_, false);
  if (!window_) return kFailure;

  worker_ = std::make_unique<Worker>([] { glfwPostEmptyEvent(); });
  window_support::watch_stop_signals(true);
  int status = 0;
  bool done = false;
  std::vector<unsigned char> shot;
  int shot_w = 0, shot_h = 0;
  penumbra::Stopwatch clock;
  double last = 0;
  while (!done && !glfwWindowShouldClose(window_) && !window_support::stop_requested()) {
    // Flying (keys held, the mouse looking) or replaying: about 120 window frames a second.
    // Otherwise asleep until input or a new frame arrives, so that the UI thread leaves the
    // cores to the worker (waking to notice a signal and a still camera's full-resolution frame).
    const bool events_due = replayed_ < replay_.events.size() && waiting_ == 0;
    glfwWaitEventsTimeout(events_due ? 0.0 : moving_ || looking_ ? 1.0 / 120 : 0.1);
    const double now = clock.ms() / 1000;
    const double dt = std::min(now - last, 0.25);
    last = now;
    penumbra::Stopwatch frame_watch;
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();

    if (replayed_ < replay_.events.size() && waiting_ == 0) {
      if (!apply_event(replay_.events[replayed_])) {
        status = kFailure;
        break;
      }
      ++replayed_;
      still_s_ = 0;
    } else if (replayed_ >= replay_.events.size()) {
      handle_input(dt);
    }
    Frame f;
    if (worker_->latest(shown_.serial, f)) {
      upload(f);
      if (!f.error.empty() && f.error != shown_.error)
        std::cerr << "penumbra view: render refused: " << f.error << "\n";
      if (f.error.empty()) {
        retoned_ += f.retoned ? 1 : 0;
        stale_ += !f.retoned && f.grid_slabs > 0 ? 1 : 0;
        if (!f.retoned) {  // a picture tone-mapped again is no frame time
          solve_ms_.push_back(f.solve_ms);
          display_ms_.push_back(f.display_ms);
          widths_.push_back(f.internal_width);
          for (const penumbra::StageTime& st : f.stages) stage_ms_[st.name].push_back(st.ms);
          update_scale(f);
        }
        if (f.version == version_) ++current_frames_;
      } else if (f.version == version_ && waiting_ > 0) {
        // A refused view ends the wait: rendering it again would be refused again.
        waiting_ = 0;
        wait_refused_ = true;
      }
      shown_ = std::move(f);
    }
    bool wait_over = false;
    if (waiting_ > 0 && current_frames_ >= waiting_) {
      waiting_ = 0;
      wait_over = true;
    }
    draw_panel();
    record_camera();
    {
      Job j = make_job();
      const bool fresh = j.version != job_.version;
      job_ = j;
      // A wait renders one view again and again, --frames every view; when a wait ends the
      // worker goes back to rendering each view once.
      if (fresh || waiting_ > 0 || args_.frames > 0 || wait_over)
        worker_->submit(j, waiting_ > 0 || args_.frames > 0);
    }

    ImDrawList* bg = ImGui::GetBackgroundDrawList();
    if (tex_w_ > 0)
      bg->AddImage((ImTextureID)(std::intptr_t)texture_, ImVec2(0, 0), ImVec2(float(w), float(h)));
    ImGui::Render();
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window_, &fw, &fh);
    glViewport(0, 0, fw, fh);
    glClearColor(0.05f, 0.05f, 0.05f, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

    const bool replay_done = replayed_ >= replay_.events.size() && waiting_ == 0;
    const bool current = replay_done && shown_.serial > 0 && shown_.version == version_;
    if (scripted && ((current && !shown_.error.empty()) || wait_refused_)) {
      std::cerr << "penumbra view: "
                << (wait_refused_ ? "a view the replay waits on" : "the last view")
                << " could not be rendered; nothing written\n";
      status = kFailure;
      break;
    }
    // Measurements end with frames of the last view (the replay's last event applied).
    if (args_.frames > 0 && current && solve_ms_.size() >= std::size_t(args_.frames)) done = true;
    // A screenshot with temporal accumulation waits for the history to fill (a still view).
    const int temporal = job_.options.temporal.frames;
    // So does one whose grid is solved a slab at a time, for the view's own grid.
    const bool settled = (temporal == 0 || shown_.temporal_frame + 1 >= std::uint64_t(temporal)) &&
                         shown_.grid_slabs == 0;
    if (!args_.screenshot.empty() && current && args_.frames == 0 && settled) done = true;
    if (done && !args_.screenshot.empty())
      shot = window_support::read_window(window_, shot_w, shot_h);
    glfwSwapBuffers(window_);
    ui_ms_.push_back(frame_watch.ms());
  }

  glfwHideWindow(window_);
  const bool interrupted = window_support::stop_requested();
  if (status == 0)
    status = window_support::scripted_end("penumbra view", !args_.screenshot.empty(), !shot.empty(),
                                          args_.frames, solve_ms_.size());
  if (status == 0) status = write_outputs(shot.empty() ? nullptr : &shot, shot_w, shot_h);
  if (status == 0 && interrupted) status = kInterrupted;
  window_support::watch_stop_signals(false);
  worker_.reset();
  window_support::close_window(window_, texture_);

  if (args_.stats) {
    std::vector<double> widths(widths_.begin(), widths_.end());
    std::printf("penumbra view: %s, %dx%d view, method %s, %zu frames\n", args_.scene.c_str(), w, h,
                sl::to_string(settings_.options.method), solve_ms_.size());
    const double mw = penumbra::median(widths);
    std::printf("  internal resolution: median %.0fx%.0f (scale %.3f)\n", mw,
                std::round(mw * h / w), mw / w);
    std::printf("  frame (render()): median %.2f ms\n", penumbra::median(solve_ms_));
    if (job_.options.temporal.grid_slabs > 0)
      std::printf("  grid slabs: %d frames showed the last grid while a new one was solved\n",
                  stale_);
    if (job_.options.temporal.frames > 0)
      std::printf(
          "  temporal accumulation: the last picture is frame %llu of its history (a "
          "pixel blends at most %d)\n",
          static_cast<unsigned long long>(shown_.temporal_frame + 1), job_.options.temporal.frames);
    for (const penumbra::StageTime& st : shown_.stages)
      std::printf("    %-22s median %7.2f ms\n", st.name.c_str(),
                  penumbra::median(stage_ms_[st.name]));
    std::printf(
        "  tone map: median %.2f ms; %d pictures tone-mapped again (the exposure alone "
        "changed)\n",
        penumbra::median(display_ms_), retoned_);
    std::printf("  window: median %.2f ms to draw a frame, %zu frames\n", penumbra::median(ui_ms_),
                ui_ms_.size());
  }
  return status;
}

}  // namespace viewer
