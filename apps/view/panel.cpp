// The viewer's panel: the method and its main options, bounces, exposure, the sun, the internal
// resolution, "Save view", and the last frame's time per stage.
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "view/viewer.hpp"

namespace sl = penumbra::spaceland;

namespace viewer {

namespace {

// A combo over power-of-two (or listed) integer choices.
bool choice(const char* label, int& value, std::initializer_list<int> values) {
  char current[32];
  std::snprintf(current, sizeof current, "%d", value);
  bool changed = false;
  if (ImGui::BeginCombo(label, current)) {
    for (int v : values) {
      char text[32];
      std::snprintf(text, sizeof text, "%d", v);
      if (ImGui::Selectable(text, v == value)) {
        changed = v != value;
        value = v;
      }
    }
    ImGui::EndCombo();
  }
  return changed;
}

template <class E>
bool enum_choice(const char* label, E& value, std::initializer_list<E> values) {
  bool changed = false;
  if (ImGui::BeginCombo(label, sl::to_string(value))) {
    for (E v : values)
      if (ImGui::Selectable(sl::to_string(v), v == value)) {
        changed = v != value;
        value = v;
      }
    ImGui::EndCombo();
  }
  return changed;
}

void section(const char* title) {
  ImGui::Separator();
  ImGui::TextUnformatted(title);
}

}  // namespace

void Viewer::draw_panel() {
  const float w = float(scene_.camera.width);
  ImGui::SetNextWindowPos(ImVec2(w, 0));
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, ImGui::GetIO().DisplaySize.y));
  ImGui::Begin("Viewer", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  Settings next = settings_;
  sl::RenderOptions& o = next.options;
  // Temporal accumulation's history length, with what the method's jitter moves.
  const auto temporal_slider = [&](const char* jitter) {
    ImGui::SliderInt("temporal frames", &next.temporal, 0, 64);
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("%s, blended into the last frames reprojected; 0: off", jitter);
  };
  section("Method");
  enum_choice(
      "method", o.method,
      {sl::Method::ssrc, sl::Method::spwi, sl::Method::surface, sl::Method::grid, sl::Method::pt});
  switch (o.method) {
    case sl::Method::ssrc:
      choice("directions", o.ssrc.directions, {4, 8, 16, 32, 64});
      choice("sectors", o.ssrc.sectors, {8, 16, 32});
      enum_choice("off screen", o.ssrc.offscreen,
                  {sl::SsrcOffscreen::sky, sl::SsrcOffscreen::world});
      temporal_slider("directions turned each frame");
      break;
    case sl::Method::spwi:
      choice("directions", o.spwi.directions, {16, 64, 256});
      enum_choice("merge", o.spwi.merge,
                  {sl::SpwiMerge::bilinear, sl::SpwiMerge::bilateral, sl::SpwiMerge::bilinear3d,
                   sl::SpwiMerge::fix, sl::SpwiMerge::minmax});
      temporal_slider("probes moved within a tile each frame");
      break;
    case sl::Method::grid:
      choice("probe spacing", o.grid.probe_spacing, {1, 2, 4});
      choice("directions", o.grid.directions, {16, 64});
      ImGui::SliderInt("slabs a frame", &next.grid_slabs, 0, 64);
      if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "a grid solved again (the sun or the levels moved) a slab at a time, the last one "
            "shown meanwhile; 0: solved whole");
      if (shown_.grid_slabs > 0)
        ImGui::Text("new grid: %llu of %llu slabs",
                    static_cast<unsigned long long>(shown_.grid_slabs_done),
                    static_cast<unsigned long long>(shown_.grid_slabs));
      break;
    case sl::Method::surface: {
      int texels = int(o.surface.texels);
      if (choice("texels", texels, {1 << 12, 1 << 14, 1 << 16, 1 << 18}))
        o.surface.texels = std::uint64_t(texels);
      choice("directions", o.surface.directions, {16, 64, 256});
      if (!args_.atlas.empty()) ImGui::TextWrapped("from %s", args_.atlas.c_str());
      break;
    }
    case sl::Method::pt:
      choice("samples per pixel", o.pt.spp, {1, 4, 16, 64});
      break;
  }
  ImGui::SliderInt("bounces", &o.bounces, 1, 8);

  section("Picture");
  bool automatic = !next.exposure;
  if (ImGui::Checkbox("auto exposure", &automatic))
    next.exposure = automatic ? std::nullopt : std::optional<float>(shown_.exposure);
  if (next.exposure)
    ImGui::SliderFloat("exposure (EV)", &*next.exposure, -16, 16, "%.2f");
  else
    ImGui::Text("exposure %.2f EV", shown_.exposure);
  if (scene_.has_sun) {
    bool moved = ImGui::SliderFloat("sun azimuth", &next.sun_azimuth, -180, 180, "%.1f");
    moved = ImGui::SliderFloat("sun elevation", &next.sun_elevation, -10, 90, "%.1f") || moved;
    if (moved) next.sun_moved = true;
  }

  section("Resolution");
  bool auto_scale = next.scale == 0;
  if (ImGui::Checkbox("from frame time", &auto_scale)) next.scale = auto_scale ? 0 : auto_scale_;
  if (auto_scale)
    ImGui::SliderFloat("target (ms)", &next.target_ms, 5, 500, "%.0f");
  else
    ImGui::SliderFloat("scale", &next.scale, 1.0f / 16, 1, "%.3f");
  ImGui::Checkbox("guided upscaling", &next.guided);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("by depth, normals and albedo at the view's pixels; off: bilinear");

  // A change the options refuse (or too much memory) is not taken; the panel says why.
  if (diff_settings(next, settings_, scene_.has_sun) != nlohmann::json()) {
    penumbra::Status ok = sl::check_options(next.options);
    if (ok) {
      sl::RenderOptions full = next.options;  // the memory a full-resolution frame needs
      full.surface.atlas = args_.atlas;
      ok = sl::check_memory(scene_, full);
    }
    if (ok) {
      settings_ = next;
      message_.clear();
    } else {
      message_ = ok.error().message;
    }
  }

  section("Camera");
  ImGui::Text("at %.3g %.3g %.3g, yaw %.1f, pitch %.1f", fly_.position.x, fly_.position.y,
              fly_.position.z, fly_.yaw, fly_.pitch);
  ImGui::Text("speed %.3g units/s (wheel; shift x4)", speed_);
  char path[512];
  std::snprintf(path, sizeof path, "%s", save_path_.c_str());
  if (ImGui::InputText("file", path, sizeof path)) save_path_ = path;
  if (ImGui::Button("Save view")) save_view_now(save_path_);
  if (!message_.empty()) ImGui::TextWrapped("%s", message_.c_str());

  section("Last frame");
  if (!shown_.error.empty()) ImGui::TextWrapped("refused: %s", shown_.error.c_str());
  ImGui::Text("%dx%d pixels, %.1f ms (%.1f fps)", shown_.internal_width, shown_.internal_height,
              shown_.solve_ms, shown_.solve_ms > 0 ? 1000 / shown_.solve_ms : 0.0);
  for (const penumbra::StageTime& st : shown_.stages)
    ImGui::Text("  %-20s %8.1f ms", st.name.c_str(), st.ms);
  ImGui::Text("  %-20s %8.1f ms", "tone map", shown_.display_ms);
  if (!shown_.line.empty()) ImGui::TextWrapped("%s", shown_.line.c_str() + 2);
  ImGui::End();
}

}  // namespace viewer
