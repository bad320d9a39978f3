// The viewer's worker thread: renders the latest view with a spaceland::Renderer (which keeps the
// BVH and the surface atlas between views) and tone-maps it, so that the window never waits for
// a slow frame.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "penumbra/penumbra.hpp"

namespace viewer {

// A view to render: the scene with the camera (at the internal resolution) and the sun set.
struct Job {
  std::shared_ptr<const penumbra::spaceland::Scene> scene;
  // Where set (an internal resolution below the view's, guided upscaling): the same scene at the
  // view's size, whose first hits guide the frame's upscaling (upscale.hpp).
  std::shared_ptr<const penumbra::spaceland::Scene> view;
  penumbra::spaceland::RenderOptions options;
  std::optional<float> exposure;  // empty: automatic
  std::uint64_t version = 0;      // changes with anything above
  std::uint64_t image = 0;        // changes with anything above but the exposure
  bool automatic = false;         // at the internal resolution the frame time chose
  float scale = 1;                // the internal resolution over the view's
};

// What the worker shows: the display picture of one render, and how long it took.
struct Frame {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;               // 8-bit sRGB, row 0 at the top
  int internal_width = 0, internal_height = 0;  // what the method rendered (then upscaled)
  std::vector<penumbra::StageTime> stages;
  double solve_ms = 0, display_ms = 0;
  double upscale_ms = 0;  // of solve_ms: the guides and the upscaling
  float exposure = 0;     // EV the picture was shown with
  std::uint64_t version = 0;
  bool automatic = false;    // Job::automatic
  float scale = 1;           // Job::scale
  std::uint64_t serial = 0;  // counts rendered frames
  // With temporal accumulation: the frame's index in its history (RenderResult::temporal_frame).
  std::uint64_t temporal_frame = 0;
  // With the grid solved a slab at a time: the new grid's slabs done and in all (0, 0: the frame
  // shows its own grid; RenderResult::grid_slabs_done, grid_slabs).
  std::uint64_t grid_slabs_done = 0, grid_slabs = 0;
  std::string line;      // the method's parameters as it used them (describe_line)
  std::string error;     // the render was refused (the picture is the previous one)
  bool retoned = false;  // the last frame's image, tone-mapped again (the exposure changed)
};

class Worker {
 public:
  // `on_frame` runs on the worker thread after each frame is published (to wake the UI).
  explicit Worker(std::function<void()> on_frame);
  // Waits for the frame in progress (the path tracer stops after its current pass).
  ~Worker();

  // The view to render once the current frame is done; `continuous`: render it again and again
  // (measurement), else once per version, or with temporal accumulation until its history holds
  // temporal.frames frames, or with the grid solved a slab at a time until the view's own grid
  // is shown (a still view then stops changing).
  void submit(Job job, bool continuous);
  // The latest frame if it is newer than `serial`.
  bool latest(std::uint64_t serial, Frame& out);

 private:
  void loop();

  std::function<void()> on_frame_;
  std::atomic<bool> cancel_{false};
  std::mutex mutex_;
  std::condition_variable wake_;
  Job job_;
  bool continuous_ = false, quit_ = false;
  Frame frame_;
  penumbra::spaceland::Renderer renderer_;  // used by the worker thread only
  // The last frame's radiance at the view's size and its Job::image: a change of the exposure
  // alone tone-maps it again instead of rendering (worker thread only).
  penumbra::ImageRgb radiance_;
  std::uint64_t radiance_image_ = 0;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace viewer
