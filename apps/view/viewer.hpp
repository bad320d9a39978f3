// The viewer's window: GLFW, OpenGL and Dear ImGui on the UI thread, the fly camera, the panel and
// the replay; a Worker renders on a thread of its own.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "penumbra/penumbra.hpp"
#include "view/fly.hpp"
#include "view/replay.hpp"
#include "view/worker.hpp"
#include "view_cmd.hpp"

struct GLFWwindow;

namespace viewer {

constexpr float kPanelWidth = 340;
constexpr float kMinHeight = 700;

class Viewer {
 public:
  // `scene` as loaded (its camera the view's size), `doc` its JSON document for "Save view".
  Viewer(const ViewArgs& args, penumbra::spaceland::Scene scene, nlohmann::json doc,
         Settings settings, Replay replay);
  // Opens the window and flies until it is closed, the replay and its frames are done, or a
  // signal arrives; writes the outputs. Exit code as run_view's.
  int run();

 private:
  void handle_input(double dt);
  bool apply_event(const Event& e);  // false: refused (printed)
  void draw_panel();
  void update_scale(const Frame& f);
  Job make_job();
  void upload(const Frame& f);
  int write_outputs(const std::vector<unsigned char>* shot, int w, int h);
  penumbra::Vec3 sun_direction() const;  // from the panel's azimuth and elevation
  void record_camera();
  void save_view_now(const std::string& path);
  penumbra::spaceland::Camera camera() const;  // the view's, at its full size

  const ViewArgs& args_;
  penumbra::spaceland::Scene scene_;  // camera: the view's size
  nlohmann::json doc_;
  Settings settings_;
  Replay replay_;
  std::size_t replayed_ = 0;
  int waiting_ = 0;  // frames a wait event still needs
  std::uint64_t wait_from_ = 0;
  Replay recorded_;
  Settings recorded_settings_;
  Fly fly_, start_fly_, recorded_fly_;
  float speed_ = 1;  // world units a second

  GLFWwindow* window_ = nullptr;
  unsigned texture_ = 0;  // GLuint
  int tex_w_ = 0, tex_h_ = 0;
  std::unique_ptr<Worker> worker_;
  Frame shown_;
  Job job_;                // the last view handed to the worker
  Settings job_settings_;  // the settings it was made with
  std::uint64_t version_ = 0;
  std::uint64_t image_version_ = 0;  // Job::image
  int current_frames_ = 0;           // frames shown of the current version
  bool wait_refused_ = false;        // a replay's wait ended on a refused view
  float auto_scale_ = 0.5f;
  double still_s_ = 0;  // seconds since the camera last moved
  bool looking_ = false, moving_ = false;
  bool quit_down_ = false, save_down_ = false;
  double look_x_ = 0, look_y_ = 0;
  std::string save_path_;
  std::string message_;
  std::vector<double> solve_ms_, display_ms_, ui_ms_;
  std::map<std::string, std::vector<double>> stage_ms_;
  std::vector<int> widths_;  // internal width of each frame
  int retoned_ = 0;          // frames that only tone-mapped the last picture again
  int stale_ = 0;            // frames that showed the last grid while a new one was solved
};

}  // namespace viewer
