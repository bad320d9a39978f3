#include "view/worker.hpp"

#include <utility>

#include "core/timer.hpp"
#include "render_options.hpp"
#include "view/upscale.hpp"

namespace sl = penumbra::spaceland;

namespace viewer {

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

void Worker::submit(Job job, bool continuous) {
  {
    std::lock_guard lock(mutex_);
    job_ = std::move(job);
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
  std::uint64_t done = 0, serial = 0;
  bool accumulating = false;  // the last frame's temporal history wants more frames of its view
  // The last rendered frame's stages, parameters and temporal index (a re-tone-mapped frame
  // shows them again).
  std::vector<penumbra::StageTime> frame_stages;
  std::string frame_line;
  std::uint64_t frame_temporal = 0;
  for (;;) {
    Job job;
    bool continuous = false;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] {
        return quit_ || (job_.scene && (continuous_ || accumulating || job_.version != done));
      });
      if (quit_) return;
      job = job_;
      continuous = continuous_;
    }
    Frame f;
    f.width = job.scene->camera.width;
    f.height = job.scene->camera.height;
    f.internal_width = f.width;
    f.internal_height = f.height;
    f.version = job.version;
    f.automatic = job.automatic;
    f.scale = job.scale;
    f.serial = ++serial;
    job.options.cancel = &cancel_;
    penumbra::Stopwatch watch;
    try {  // the library reports errors as values; anything thrown here is shown, not fatal
      penumbra::Expected<sl::RenderResult> r = sl::RenderResult{};
      const bool retone = job.image == radiance_image_ && !continuous && !accumulating;
      if (retone) {  // the exposure alone changed: the last radiance, tone-mapped again
        f.retoned = true;
        r->radiance = radiance_;
        r->stages = frame_stages;
      } else {
        r = renderer_.render(*job.scene, job.options);
        f.solve_ms = watch.ms();
        if (r && job.view) {  // brought to the view's size, guided by its first hits
          watch.restart();
          penumbra::Expected<std::vector<penumbra::ImageRgb>> low =
              renderer_.channels(*job.scene, kGuideChannels, job.options);
          penumbra::Expected<std::vector<penumbra::ImageRgb>> high =
              low ? renderer_.channels(*job.view, kGuideChannels, job.options) : low;
          if (!high) {
            r = high.error();
          } else {
            r->radiance = upscale(r->radiance, Guide::from(std::move(*low)),
                                  Guide::from(std::move(*high)), !job.scene->media.empty());
            f.upscale_ms = watch.ms();
            r->stages.push_back({"upscale", f.upscale_ms});
            f.solve_ms += f.upscale_ms;
          }
        }
      }
      if (r && job.view) {
        f.width = job.view->camera.width;
        f.height = job.view->camera.height;
      }
      accumulating = false;
      if (r) {
        if (!retone) {
          radiance_ = r->radiance;
          radiance_image_ = job.image;
          frame_stages = r->stages;
          frame_line = sl::describe_line(*r);
          frame_temporal = r->temporal_frame;
        }
        f.temporal_frame = frame_temporal;
        const int frames = job.options.temporal.frames;
        accumulating = !retone && frames > 0 && r->temporal_frame + 1 < std::uint64_t(frames);
        if (!retone) {
          f.grid_slabs_done = r->grid_slabs_done;
          f.grid_slabs = r->grid_slabs;
          accumulating = accumulating || r->grid_slabs > 0;  // the view's grid is under way
        }
        f.stages = std::move(r->stages);
        f.line = frame_line;
        watch.restart();
        f.exposure =
            job.exposure ? *job.exposure : sl::auto_exposure(r->radiance, sl::Aov::radiance);
        f.rgb = sl::display_picture(r->radiance, sl::Aov::radiance, {f.exposure}).rgb;
        f.display_ms = watch.ms();
      } else {
        radiance_image_ = 0;
        f.error = with_flags(r.error().message);
      }
    } catch (const std::exception& e) {
      radiance_image_ = 0;
      f.rgb.clear();
      f.error = std::string("internal error: ") + e.what();
    }
    done = job.version;
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

}  // namespace viewer
