// The painter's panel (Dear ImGui): frame times, brush, environment, method settings, files.
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "paint/window.hpp"

using namespace penumbra;
using namespace penumbra::flatland;

namespace painter {

void Painter::draw_panel() {
  const float z = zoom();
  ImGui::SetNextWindowPos(ImVec2(canvas_.width() * z, 0));
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, ImGui::GetIO().DisplaySize.y));
  ImGui::Begin("Penumbra painter", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::Text("grid %d x %d cells, zoom %.2f", canvas_.width(), canvas_.height(), z);

  // The frame: per stage, as the solver measured it.
  if (ImGui::CollapsingHeader("Frame", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Text("method %s on %s, frame %llu", to_string(options_.method), shown_.device.c_str(),
                (unsigned long long)shown_.serial);
    ImGui::Text("solve %.1f ms (%.0f fps), display %.1f ms", shown_.solve_ms,
                shown_.solve_ms > 0 ? 1000.0 / shown_.solve_ms : 0.0, shown_.display_ms);
    if (ImGui::TreeNode("stages", "%zu stages", shown_.stages.size())) {
      for (const StageTime& s : shown_.stages) ImGui::Text("%-22s %7.2f ms", s.name.c_str(), s.ms);
      ImGui::TreePop();
    }
    ImGui::Text("window: %.1f ms to draw a frame", ui_ms_.empty() ? 0.0 : ui_ms_.back());
    if (!shown_.error.empty()) ImGui::TextWrapped("render refused: %s", shown_.error.c_str());
  }

  if (ImGui::CollapsingHeader("Brush", ImGuiTreeNodeFlags_DefaultOpen)) {
    int tool = int(brush_.tool);
    ImGui::RadioButton("light", &tool, int(paint::Tool::light));
    ImGui::SameLine();
    ImGui::RadioButton("wall", &tool, int(paint::Tool::wall));
    ImGui::SameLine();
    ImGui::RadioButton("fog", &tool, int(paint::Tool::fog));
    ImGui::SameLine();
    ImGui::RadioButton("eraser", &tool, int(paint::Tool::erase));
    brush_.tool = paint::Tool(tool);
    if (brush_.tool != paint::Tool::erase)
      ImGui::ColorEdit3(brush_.tool == paint::Tool::light ? "colour" : "albedo", &brush_.color.r);
    if (brush_.tool == paint::Tool::light)
      ImGui::SliderFloat("intensity", &brush_.intensity, 0.01f, canvas_.emission_scale(), "%.2f",
                         ImGuiSliderFlags_Logarithmic);
    if (brush_.tool == paint::Tool::fog)
      ImGui::SliderFloat("opacity", &brush_.opacity, 0.001f, 0.99f, "%.3f",
                         ImGuiSliderFlags_Logarithmic);
    ImGui::SliderFloat("radius", &brush_.radius, 0.5f, paint::kMaxBrushRadius, "%.1f cells",
                       ImGuiSliderFlags_Logarithmic);
    ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
    ImGui::TextWrapped("keys 1-4: tool; wheel: radius; Ctrl-Z: undo; Ctrl-S: save; Ctrl-Q: quit");
    ImGui::PopStyleColor();
    if (ImGui::Button("Undo") && canvas_.undo() && !recorded_.empty()) recorded_.pop_back();
    ImGui::SameLine();
    if (ImGui::Button("Clear")) {
      canvas_.clear();
      // A stroke file has no "clear": record an eraser covering every cell.
      const float w = float(canvas_.width()), h = float(canvas_.height());
      paint::Brush e;
      e.tool = paint::Tool::erase;
      e.radius = std::min(std::hypot(w, h), paint::kMaxBrushRadius);
      paint::Stroke s{e, {}};
      for (float y = 0; y < h + e.radius; y += e.radius)
        for (float x = 0; x < w + e.radius; x += e.radius) s.points.push_back({x, y});
      recorded_.push_back(std::move(s));
    }
    ImGui::SameLine();
    ImGui::Text("%zu undo steps", canvas_.undo_steps());
  }

  if (ImGui::CollapsingHeader("Environment", ImGuiTreeNodeFlags_DefaultOpen)) {
    bool changed = ImGui::ColorEdit3("colour##env", &environment_.r);
    changed |= ImGui::SliderFloat("radiance", &environment_intensity_, 0.0f, 4.0f, "%.3f",
                                  ImGuiSliderFlags_Logarithmic);
    if (changed)
      canvas_.set_environment({environment_.r * environment_intensity_,
                               environment_.g * environment_intensity_,
                               environment_.b * environment_intensity_});
  }

  if (ImGui::CollapsingHeader("Method", ImGuiTreeNodeFlags_DefaultOpen)) {
    bool changed = false;
    int m = int(options_.method);
    const char* names[] = {to_string(Method(0)), to_string(Method(1)), to_string(Method(2))};
    if (ImGui::Combo("method", &m, names, 3)) options_.method = Method(m), changed = true;
    int device = int(options_.device);
    const char* devices[] = {to_string(Device(0)), to_string(Device(1)), to_string(Device(2))};
    if (ImGui::Combo("device", &device, devices, 3))
      options_.device = Device(device), changed = true;
    changed |= ImGui::SliderInt("bounces", &options_.bounces, 1, 8);
    changed |= ImGui::SliderInt("threads", &options_.threads, 0,
                                int(std::max(1u, std::thread::hardware_concurrency())),
                                options_.threads == 0 ? "all" : "%d");
    if (options_.method == Method::hrc) {
      bool f16 = options_.hrc.storage == Storage::f16;
      if (ImGui::Checkbox("f16 storage", &f16))
        options_.hrc.storage = f16 ? Storage::f16 : Storage::f32, changed = true;
      // Two checkboxes a line, so that the panel fits the window with every section open.
      ImGui::SameLine(kPanelWidth / 2);
      changed |= ImGui::Checkbox("cross blur", &options_.hrc.cross_blur);
      changed |= ImGui::Checkbox("blur near segment", &options_.hrc.blur_near);
      ImGui::SameLine(kPanelWidth / 2);
      changed |= ImGui::Checkbox("near segment", &options_.hrc.near_segment);
      bool walls = options_.hrc.corners == Corners::walls;
      if (ImGui::Checkbox("corners: walls only", &walls))
        options_.hrc.corners = walls ? Corners::walls : Corners::half, changed = true;
      changed |= ImGui::SliderInt("wall fan", &options_.hrc.wall_fan, 0, kMaxWallFan);
      changed |= ImGui::SliderFloat("fan share", &options_.hrc.fan_share, 1.0f / 1024, 1.0f, "%.4f",
                                    ImGuiSliderFlags_Logarithmic);
      changed |= ImGui::SliderInt("near fan", &options_.hrc.near_fan, 0, kMaxNearFan);
      changed |= ImGui::SliderFloat("even weight", &options_.hrc.even_weight, 0.0f, 1.0f, "%.3f");
    } else if (options_.method == Method::rc) {
      RcOptions& rc = options_.rc;
      changed |= ImGui::SliderInt("probe spacing", &rc.probe_spacing, 1, 16);
      changed |= ImGui::SliderInt("directions Q0", &rc.directions, 1, 16);
      changed |= ImGui::SliderFloat("interval t0", &rc.interval, 0.5f, 64.0f, "%.1f",
                                    ImGuiSliderFlags_Logarithmic);
      int fix = int(rc.fix);
      const char* fixes[] = {"bilinear fix", "vanilla", "nearest"};
      if (ImGui::Combo("merge", &fix, fixes, 3)) rc.fix = MergeFix(fix), changed = true;
    } else {
      changed |= ImGui::SliderInt("spp", &options_.pt.spp, 1, 256);
      changed |= ImGui::Checkbox("next event estimation", &options_.pt.nee);
    }
    changed |= ImGui::Checkbox("auto exposure", &look_.auto_exposure);
    if (look_.auto_exposure) {
      ImGui::SameLine();
      ImGui::Text("%+.1f EV", shown_.exposure);
      look_.exposure = shown_.exposure;  // the slider starts from it when turned off
    } else {
      changed |= ImGui::SliderFloat("exposure (EV)", &look_.exposure, -8.0f, 8.0f, "%.1f");
    }
    changed |= ImGui::Checkbox("show walls and fog", &look_.materials);
    ImGui::SameLine(kPanelWidth / 2);
    ImGui::Checkbox("solve every frame", &continuous_);
    if (changed) ++options_version_;
  }

  if (ImGui::CollapsingHeader("File", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::InputText("scene file", &file_);
    if (ImGui::Button("Save")) {
      Status s = canvas_.save(file_);
      message_ = s ? "saved " + file_ + "; as shown here: " +
                         painter::render_command(file_, options_, look_, shown_.exposure)
                   : s.error().message;
    }
    ImGui::SameLine();
    if (ImGui::Button("Load")) {
      Expected<SceneDesc> desc = load_scene(file_);
      Expected<paint::Canvas> c =
          desc ? paint::Canvas::from_scene(*desc,
                                           args_.emission_scale_given ? args_.emission_scale : 0)
               : Expected<paint::Canvas>(desc.error());
      if (c)
        if (Status m = painter_memory(c->width(), c->height(), options_); !m) c = m.error();
      if (c) {
        replace_canvas(std::move(*c));
        message_ = "loaded " + file_;
      } else {
        message_ = c.error().message;
      }
    }
    ImGui::TextDisabled("emission scale %g", canvas_.emission_scale());
    if (!message_.empty()) ImGui::TextWrapped("%s", message_.c_str());
  }
  ImGui::End();
}

}  // namespace painter
