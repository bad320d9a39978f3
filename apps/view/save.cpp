#include "view/save.hpp"

#include <filesystem>
#include <sstream>

#include "io/image_io.hpp"
#include "io/json_reader.hpp"
#include "render_options.hpp"

using nlohmann::json;
namespace fs = std::filesystem;
namespace sl = penumbra::spaceland;

namespace viewer {

namespace {

json vec(penumbra::Vec3 v) {
  return json::array({v.x, v.y, v.z});  // floats: they read back as the same floats
}

}  // namespace

json saved_view(json doc, const std::string& from, const std::string& to, const sl::Camera& c,
                const std::optional<penumbra::Vec3>& sun) {
  doc["camera"] = {{"position", vec(c.position)},
                   {"look_at", vec(c.look_at)},
                   {"up", vec(c.up)},
                   {"fov_y", c.fov_y},
                   {"width", c.width},
                   {"height", c.height}};
  if (sun && doc.contains("sun") && doc["sun"].is_object()) doc["sun"]["direction"] = vec(*sun);
  // Mesh files are relative to the scene file: kept pointing at the same files from `to`.
  const fs::path from_dir = fs::absolute(from).parent_path(),
                 to_dir = fs::absolute(to).parent_path();
  if (from_dir.lexically_normal() != to_dir.lexically_normal() && doc.contains("objects") &&
      doc["objects"].is_array())
    for (json& o : doc["objects"])
      if (o.is_object() && o.contains("file") && o["file"].is_string()) {
        const fs::path f = o["file"].get<std::string>();
        if (f.is_absolute()) continue;
        const fs::path target = (from_dir / f).lexically_normal();
        fs::path rel = target.lexically_relative(to_dir);
        o["file"] = (rel.empty() ? target : rel).generic_string();
      }
  return doc;
}

penumbra::Status save_view(const json& doc, const std::string& to) {
  return penumbra::io::write_text_files({{to, doc.dump(2) + "\n"}});
}

std::string render_command(const std::string& file, const Settings& s, const std::string& atlas,
                           const std::string& max_memory) {
  const sl::RenderOptions& o = s.options;
  std::ostringstream c;
  c << "penumbra render " << file << " --method " << sl::to_string(o.method);
  if (o.bounces != 1) c << " --bounces " << o.bounces;
  if (o.threads != 0) c << " --threads " << o.threads;
  if (o.max_memory != sl::RenderOptions{}.max_memory) c << " --max-memory " << max_memory;
  // The method's own settings where they differ from render's defaults (the panel's fields).
  const std::string prefix = std::string(sl::to_string(o.method)) + ".";
  Settings defaults;
  defaults.options.method = o.method;
  const json d = diff_settings(s, defaults, false);
  if (d.is_object())
    for (const auto& [key, value] : d.items()) {
      if (!key.starts_with(prefix)) continue;
      const std::vector<std::string> flags = flags_of(key);
      if (flags.empty()) continue;
      c << " " << flags[0] << " " << (value.is_string() ? value.get<std::string>() : value.dump());
    }
  if (o.method == sl::Method::surface && !atlas.empty()) c << " --atlas " << atlas;
  if (s.exposure) c << " --exposure " << penumbra::io::format_number(*s.exposure);
  c << " -o out.png";
  return c.str();
}

}  // namespace viewer
