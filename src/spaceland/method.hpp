// The 3D methods as a table: one entry per method (its name, the options it reads, their check,
// what it asks of the scene, its memory estimate, how it describes a render, whether it follows
// bounces itself, and its solve per device) that the dispatcher (render.cpp), the command line's
// option groups and refusals, and the memory check read. A new method is a new entry
// (docs/ARCHITECTURE.md, "Adding a 3D method"); nothing else branches on the method.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "penumbra/spaceland/render.hpp"
#include "spaceland/solve.hpp"

namespace penumbra::spaceland {

// What a render derives once, before anything is allocated: the options checked, and how later
// bounces are had.
struct Plan {
  RenderOptions options;
  int width = 0, height = 0;  // the camera's image
  // Later bounces from the radiance cache (a method that does not follow them, bounces > 1).
  bool radiance_cache = false;
  // The light is rendered at 2^-light_exponent and scaled back (spaceland/brightness.hpp).
  int light_exponent = 0;
  std::uint64_t pixels() const { return std::uint64_t(width) * std::uint64_t(height); }
};

// A solve: the image, what it reports, and in `used` the options with the values it derived.
using Solve = Expected<ImageRgb> (*)(const SolveContext& ctx, const RenderOptions& options,
                                     SolveReport& report, RenderOptions& used);

struct MethodEntry {
  Method method;
  const char* name;     // as to_string(), the command line and --json name it
  const char* title;    // in messages: "the path tracer"
  const char* summary;  // one line for --help
  // The RenderOptions fields it reads (MethodInfo::options).
  std::span<const char* const> options;
  // Whether, with these options, the method follows light through every bounce itself;
  // otherwise the dispatcher hands it a radiance cache holding bounces 2..N at the surfaces
  // (RadianceCache, its options `grid`).
  bool (*bounces_itself)(const RenderOptions& options);
  // The ranges and combinations of its own options, before any scene is read; fields named as
  // in RenderOptions (`spwi.directions`). Null: none of its own.
  Status (*check_options)(const RenderOptions& options);
  // What it cannot render (SPWI: fog). Null: any scene that passes check_scene.
  Status (*check_scene)(const Scene& scene);
  // Its working memory besides the BVH, the G-buffer, the image and the radiance cache.
  std::uint64_t (*working_bytes)(const Scene& scene, const RenderOptions& options);
  // Its parameters as a render used them, and the same in a few words.
  void (*describe)(const RenderResult& result, std::vector<Parameter>& parameters,
                   std::string& line);
  Solve cpu;
  Solve gpu;  // null: the CPU only
};

// Every method, in the order of the Method enum.
std::span<const MethodEntry> method_table();
// The entry of a method (m must be one of the enum's: make_plan refuses others).
const MethodEntry& entry(Method m);

// Checks the options (those every method shares, the method's own, the radiance cache's when it
// is needed) and the scene (the format's rules, what the method cannot render).
Expected<Plan> make_plan(const Scene& scene, const RenderOptions& options);

}  // namespace penumbra::spaceland
