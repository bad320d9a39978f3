// The painter's worker thread: renders the latest canvas from scratch (no temporal reuse, as in
// the papers) and tone-maps it, so that the window never waits for a slow frame.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "penumbra/penumbra.hpp"

namespace painter {

// How the fluence is shown.
struct Look {
  float exposure = 0;         // EV, when not automatic
  bool auto_exposure = true;  // each frame's exposure from its picture (flatland::auto_exposure)
  bool materials = true;      // walls and fog stay visible where no light reaches them
};

// The `penumbra render` command that renders the scene file `file` as the window shows it: the
// method and its options where they differ from render's defaults, the bounces, and the look.
std::string render_command(const std::string& file, const penumbra::flatland::RenderOptions& o,
                           const Look& look, float exposure);

// What the worker shows: the display picture of one render, and how long it took.
struct Frame {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;  // 8-bit sRGB, row 0 at the top
  std::vector<penumbra::flatland::StageTime> stages;
  double solve_ms = 0, display_ms = 0;
  float exposure = 0;  // EV the picture was shown with
  std::uint64_t scene_version = 0, options_version = 0;
  std::uint64_t serial = 0;  // counts solved frames
  std::string device;        // what rendered it
  std::string error;         // the render was refused (the picture is the previous one)
};

class Worker {
 public:
  // `on_frame` runs on the worker thread after each frame is published (to wake the UI).
  explicit Worker(std::function<void()> on_frame);
  // Waits for the frame in progress (a progressive method stops after its current pass).
  ~Worker();

  // Hands the worker a new canvas state; it is rendered once the current frame is done.
  void submit(std::shared_ptr<const penumbra::flatland::Scene> scene, std::uint64_t scene_version,
              const penumbra::flatland::RenderOptions& options, std::uint64_t options_version,
              const Look& look, bool continuous);

  // The latest frame if it is newer than `serial`.
  bool latest(std::uint64_t serial, Frame& out);

 private:
  void loop();

  std::function<void()> on_frame_;
  std::atomic<bool> cancel_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
  std::shared_ptr<const penumbra::flatland::Scene> scene_;
  std::uint64_t scene_version_ = 0, options_version_ = 0;
  penumbra::flatland::RenderOptions options_;
  Look look_;
  bool continuous_ = false, quit_ = false;
  Frame frame_;
  // Keeps its buffers from frame to frame (used by the worker thread only).
  penumbra::flatland::Renderer renderer_;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace painter
