#include "paint/worker.hpp"

#include <algorithm>
#include <sstream>
#include <utility>

#include "core/timer.hpp"
#include "render_options.hpp"

using namespace penumbra;
using namespace penumbra::flatland;

namespace painter {

std::string render_command(const std::string& file, const RenderOptions& o, const Look& look,
                           float exposure) {
  const RenderOptions d;  // render's defaults
  std::ostringstream c;
  c << "penumbra render " << file << " --method " << to_string(o.method);
  if (o.bounces != d.bounces) c << " --bounces " << o.bounces;
  if (o.method == Method::hrc) {
    const HrcOptions &h = o.hrc, &hd = d.hrc;
    if (h.storage != hd.storage) c << " --storage " << to_string(h.storage);
    if (!h.cross_blur) c << " --no-cross-blur";
    if (h.blur_near) c << " --blur-near-segment";
    if (!h.near_segment) c << " --no-near-segment";
    if (h.corners != hd.corners) c << " --corners " << to_string(h.corners);
    if (h.wall_fan != hd.wall_fan) c << " --wall-fan " << h.wall_fan;
    if (h.fan_share != hd.fan_share) c << " --fan-share " << h.fan_share;
    if (h.near_fan != hd.near_fan) c << " --near-fan " << h.near_fan;
    if (h.even_weight != hd.even_weight) c << " --even-weight " << h.even_weight;
  } else if (o.method == Method::rc) {
    const RcOptions &r = o.rc, &rd = d.rc;
    if (r.probe_spacing != rd.probe_spacing) c << " --probe-spacing " << r.probe_spacing;
    if (r.directions != rd.directions) c << " --directions " << r.directions;
    if (r.interval != rd.interval) c << " --interval " << r.interval;
    if (r.fix != rd.fix) c << " --fix " << to_string(r.fix);
  } else {
    c << " --spp " << o.pt.spp;
    if (o.pt.nee) c << " --nee";
  }
  if (!look.auto_exposure) c << " --exposure " << exposure;
  if (!look.materials) c << " --no-show-walls";
  c << " -o out.png";
  return c.str();
}

Worker::Worker(std::function<void()> on_frame)
    : on_frame_(std::move(on_frame)), thread_([this] { loop(); }) {}

Worker::~Worker() {
  {
    std::lock_guard lock(mutex_);
    quit_ = true;
  }
  cancel_.store(true);
  wake_.notify_all();
  thread_.join();
}

void Worker::submit(std::shared_ptr<const Scene> scene, std::uint64_t scene_version,
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

bool Worker::latest(std::uint64_t serial, Frame& out) {
  std::lock_guard lock(mutex_);
  if (frame_.serial == serial) return false;
  out = frame_;
  return true;
}

void Worker::loop() {
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
        f.exposure = look.auto_exposure ? auto_exposure(r->fluence, scene.get()) : look.exposure;
        f.rgb = display_picture(r->fluence, scene.get(), {f.exposure, look.materials}).rgb;
        f.display_ms = watch.ms();
      } else {
        f.error = with_flags(r.error().message);
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

}  // namespace painter
