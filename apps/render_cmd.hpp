// `penumbra render`: one scene, one method, images out.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "penumbra/flatland/render.hpp"
#include "penumbra/spaceland/render.hpp"
#include "render_options.hpp"

namespace CLI {
class App;
}

struct RenderArgs {
  std::string scene;   // empty: the built-in scene
  std::string method;  // empty: the world's default (rc in 2D, pt in 3D)
  // 3D only: the camera's image size (0: the scene's) and what the image holds.
  int width = 0, height = 0;
  penumbra::spaceland::Aov aov = penumbra::spaceland::Aov::radiance;
  // 3D spwi: its own options (those in kSpwiSharedOptions are read into 2D's `options.rc` and
  // copied when given).
  penumbra::spaceland::SpwiOptions spwi;
  penumbra::spaceland::GridOptions grid;
  // 3D ssrc: its own options (--sectors, --march-rays, --thickness); those it shares with spwi
  // and 2D's cascades are copied when given.
  penumbra::spaceland::SsrcOptions ssrc;
  // 3D surface: its own options (--texel-size, --texels); --directions, --interval and
  // --cascades are copied when given.
  penumbra::spaceland::SurfaceOptions surface;

  int cache_probe_spacing = penumbra::spaceland::RenderOptions{}.cache_probe_spacing;
  int sun_rays = penumbra::spaceland::RenderOptions{}.sun_rays;
  bool disjoint = false;  // --disjoint: spwi's thesis intervals (SpwiOptions::overlap off)
  std::vector<std::string> outputs;
  std::string max_memory = "8G";
  std::optional<float> exposure;  // --exposure; empty: chosen from the picture (auto_exposure)
  // --exposure-from: the image the automatic exposure is metered on instead.
  std::string exposure_from;
  bool show_walls = true;  // 2D PNGs: walls and fog in the dark keep a dim floor of their colour
  bool json = false;
  bool quiet = false;
  penumbra::flatland::RenderOptions options;
  RenderOptionFlags flags;        // applied to `options` by run_render
  const CLI::App* app = nullptr;  // the subcommand, to tell which options were given
};

struct RenderCommand {
  CLI::App* app = nullptr;
  RenderArgs args;
  bool parsed() const;
};

// Registers the subcommand on `app`; its options write into the returned command's args.
std::unique_ptr<RenderCommand> add_render_command(CLI::App& app);

// Exit code: 0 success, 1 bad input or failure, 2 usage error, 130 interrupted (the image of the
// samples so far is still written).
int run_render(const RenderArgs& args);

// The options only a 3D render reads (render_cmd.cpp refuses them with a 2D scene); which 3D
// method reads which option comes from the method table (MethodInfo::options, by flags_of).
inline constexpr std::string_view k3dOptions[] = {"--width", "--height", "--aov"};

// The 2D methods' own options: render_cmd.cpp refuses one given with another 2D method.
inline constexpr std::string_view kPt2dOptions[] = {"--spp", "--time", "--nee", "--sampler",
                                                    "--seed"};
inline constexpr std::string_view kRc2dOptions[] = {
    "--probe-spacing", "--directions", "--branching", "--interval",     "--cascades",
    "--fix",           "--preaverage", "--extend",    "--extend-length"};
inline constexpr std::string_view kHrc2dOptions[] = {
    "--storage",         "--no-cross-blur", "--blur-near-segment", "--corners",
    "--no-near-segment", "--wall-fan",      "--near-fan",          "--even-weight"};
// Read by the 2D methods that jump over empty space (MethodEntry::skips_empty_space).
inline constexpr std::string_view kTraversalOptions[] = {"--no-distance-field", "--no-blocks"};

template <std::size_t N>
bool listed(const std::string& name, const std::string_view (&list)[N]) {
  for (std::string_view n : list)
    if (name == n) return true;
  return false;
}

// What both worlds check before loading a scene: output types and writability, --max-memory
// (parsed into `max_memory`). Prints the message; returns 0 or the exit code.
int check_render_args(const RenderArgs& args, std::uint64_t& max_memory);

// The --exposure-from image, read before the render so that a bad file fails first (empty without
// the option). Prints the message; returns 0 or the exit code.
int read_exposure_source(const RenderArgs& args, std::optional<penumbra::ImageRgb>& image);

// Whether any output is a PNG (the one output that is exposed).
bool has_png(const std::vector<std::string>& outputs);

// The exposure of the PNGs among the outputs: --exposure, or `meter()`'s reading of the
// picture; none when no PNG is written (the meter's pass over the image is then skipped).
template <class Meter>
std::optional<float> png_exposure(const RenderArgs& args, Meter&& meter) {
  if (!has_png(args.outputs)) return std::nullopt;
  return args.exposure ? *args.exposure : meter();
}

// The text report's line for it (nothing without a PNG).
void print_png_exposure(const RenderArgs& args, std::optional<float> exposure);

// Whether some 3D method reads the option named `flag` (render3d_cmd.cpp).
bool read_by_3d_method(const std::string& flag);

// The 3D half of `render` (render3d_cmd.cpp): `args.scene` is a 3D document.
int render_scene_3d(const RenderArgs& args);
