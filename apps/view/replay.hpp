// What the viewer's panel sets (Settings) and the replay files that drive it and the camera
// (docs/VIEWER.md, "Replay files"): read with messages naming the file and the JSON path, and
// written back by --record.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "penumbra/error.hpp"
#include "penumbra/spaceland/render.hpp"

namespace viewer {

// The panel: the method and its options, and how frames are shown.
struct Settings {
  penumbra::spaceland::RenderOptions options;  // method, bounces, the methods' options, threads
  std::optional<float> exposure;               // EV; empty: each frame's automatic exposure
  float scale = 0;       // internal resolution over the view's, in (0, 1]; 0: from target_ms
  float target_ms = 33;  // the frame time the automatic scale aims at
  // Below the view's resolution: upscaled guided by the first hits (upscale.hpp), or bilinearly.
  bool guided = true;
  // ssrc's and spwi's temporal accumulation: the history's length in frames
  // (RenderOptions::temporal; 0: off). The other methods draw the same image every frame and take
  // none.
  int temporal = 0;
  // The grid's solve spread over frames, this many slabs a frame (RenderOptions::temporal's
  // grid_slabs; 0: off).
  int grid_slabs = 0;
  // The sun, where the scene has one: degrees about the scene camera's up from its heading, and
  // above the horizon.
  float sun_azimuth = 0, sun_elevation = 0;
  bool sun_moved = false;  // else the scene's own direction (exactly as its file says)
};

// One replay step, applied on one window frame.
struct Event {
  enum class Kind { camera, move, set, wait };
  Kind kind = Kind::wait;
  // camera: where the fly camera goes: yaw in degrees from the scene camera's heading (turning
  // right), pitch in degrees above the plane normal to its up.
  penumbra::Vec3 position;
  float yaw = 0, pitch = 0;
  // move: right, up and forward in world units, and a turn in degrees.
  penumbra::Vec3 by;
  float turn_yaw = 0, turn_pitch = 0;
  // set: the panel's new settings (the fields the event names changed, the others kept).
  nlohmann::json set;
  // wait: frames to render of the state reached before the next event.
  int frames = 0;
};

struct Replay {
  std::vector<Event> events;
};

// Reads a replay file. Errors name the file and the JSON path ("r.json: events[2].set.bounces:
// expected an integer in 1..64, found 0").
penumbra::Expected<Replay> load_replay(const std::string& path);
// Applies a set event's fields to `s` (checked as load_replay checks them); `where` names the
// event in messages.
penumbra::Status apply_set(const nlohmann::json& set, const std::string& where, Settings& s,
                           bool has_sun);
// The JSON of `s`'s fields that differ from `from` (a set event), or null when none do.
nlohmann::json diff_settings(const Settings& s, const Settings& from, bool has_sun);
// A replay file's text.
std::string replay_json(const Replay& r);

}  // namespace viewer
