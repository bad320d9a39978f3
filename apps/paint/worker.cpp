#include "paint/worker.hpp"

#include <algorithm>
#include <utility>

#include "core/timer.hpp"
#include "render_options.hpp"

using namespace penumbra;
using namespace penumbra::flatland;

namespace painter {

namespace {

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

}  // namespace

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
        f.rgb = display_picture(r->fluence, scene.get(), {look.exposure}).rgb;
        if (look.materials) show_materials(*scene, f.rgb);
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
