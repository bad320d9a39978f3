// "Save view": the scene document with the viewer's camera (and sun), and the `penumbra render`
// command that draws the same frame at full resolution.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "penumbra/error.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "view/replay.hpp"

namespace viewer {

// `doc` (the scene file `from` as read) with its camera replaced by `camera` and, where given,
// its sun's direction by `sun`; mesh files named relative to `from`'s folder are renamed
// relative to `to`'s, so that the saved file loads the same meshes.
nlohmann::json saved_view(nlohmann::json doc, const std::string& from, const std::string& to,
                          const penumbra::spaceland::Camera& camera,
                          const std::optional<penumbra::Vec3>& sun);
// Writes it atomically.
penumbra::Status save_view(const nlohmann::json& doc, const std::string& to);

// The render command that draws the saved file as the viewer shows it at full resolution: the
// method and its options where they differ from render's defaults, bounces, threads, atlas, and
// the exposure where it is not automatic.
// `max_memory`: the --max-memory the viewer was given (the grid's voxels and every refusal
// depend on it), printed where it is not render's default.
std::string render_command(const std::string& file, const Settings& s, const std::string& atlas,
                           const std::string& max_memory);

}  // namespace viewer
