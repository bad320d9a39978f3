// The render options that `render` and `paint` share, registered by one function so that their
// names, values and checks cannot drift apart. Where the commands differ (help, ranges, the
// order of the methods), the command says so in its RenderOptionSet.
#pragma once

#include <string>
#include <vector>

#include "penumbra/flatland/render.hpp"

namespace CLI {
class App;
class Option;
}  // namespace CLI

// Which groups to register, in this order, and the help and ranges that differ by command.
// A command may call add_render_options more than once with different groups, to keep its own
// options between them (the help lists options in the order they were added).
struct RenderOptionSet {
  bool method = false;     // --method
  bool pt = false;         // --spp --time --nee --sampler --seed
  bool rc = false;         // --probe-spacing ... --extend-length
  bool device = false;     // --device
  bool storage = false;    // --storage
  bool hrc = false;        // --no-cross-blur --blur-near-segment --no-near-segment
  bool bounces = false;    // --bounces
  bool threads = false;    // --threads
  bool traversal = false;  // --no-distance-field --no-blocks

  // `render`'s wording; `paint` says its own.
  // Empty: every method of the library's table, in its order, each with its line of help.
  std::vector<penumbra::flatland::Method> methods;
  std::string method_help = "Method";
  std::string device_help =
      "cpu; gpu (Vulkan, a CPU driver such as lavapipe included; 3D: ssrc only); auto (a "
      "hardware GPU when there is one and the method runs there, else the CPU; 3D: the CPU)";
  int max_bounces = 64;
  std::string bounces_help = "Diffuse bounces (1: direct light only)";
  std::string threads_help = "Worker threads (0: all cores)";
};

// What the parse leaves besides the options themselves: options that are spelled as "not"
// and whether --spp and --time were given. finish_render_options applies them.
struct RenderOptionFlags {
  bool no_cross_blur = false;
  bool no_near_segment = false;
  bool no_distance_field = false;
  bool no_blocks = false;
  CLI::Option* spp = nullptr;  // null unless the pt group was registered
  CLI::Option* time = nullptr;
};

// `options` and `flags` must outlive the parse; `options` holds the defaults the help shows.
void add_render_options(CLI::App* app, penumbra::flatland::RenderOptions& options,
                        RenderOptionFlags& flags, const RenderOptionSet& which);

// After the parse: the "not" flags, and --time without --spp meaning no sample limit.
void finish_render_options(penumbra::flatland::RenderOptions& options,
                           const RenderOptionFlags& flags);

// The library names options by their RenderOptions field in messages (`rc.probe_spacing`); the
// command line shows `message` with each such field replaced by the flag registered above for it.
std::string with_flags(std::string message);

// The flags that set a RenderOptions field (`field` as the library names it: "spwi.merge"); a
// method's option group is the flags of the fields its MethodInfo lists.
std::vector<std::string> flags_of(const std::string& field);
