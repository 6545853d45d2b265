#include "app/viewer/panels.h"

#include "app/viewer/viewer_app.h"
#include "geometry/deform/pose/pose_editor.h"

#include <imgui.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

namespace vox::app {

void Panels::draw(Viewer& viewer) {
  ImGui::SetNextWindowPos(ImVec2(0, 0), ImGuiCond_Always);
  int fw = 0, fh = 0;
  viewer.framebufferSize(fw, fh);
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, float(fh)), ImGuiCond_Always);
  ImGui::Begin("voxmorph", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  if (ImGui::CollapsingHeader("Pose", ImGuiTreeNodeFlags_DefaultOpen)) posePanel(viewer);
  if (ImGui::CollapsingHeader("Joints", ImGuiTreeNodeFlags_DefaultOpen)) joints_.draw(viewer);
  if (ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen)) viewPanel(viewer);
  if (ImGui::CollapsingHeader("Live figures", ImGuiTreeNodeFlags_DefaultOpen)) figuresPanel(viewer);
  if (ImGui::CollapsingHeader("Organs", ImGuiTreeNodeFlags_DefaultOpen)) organsPanel(viewer);
  ImGui::End();
  exportBox(viewer, fw, fh);
}

void Panels::posePanel(Viewer& viewer) {
  PoseEditor& editor = viewer.editor();
  if (ImGui::Button("Undo") ) { editor.undo(); viewer.applyView(); }
  ImGui::SameLine();
  if (ImGui::Button("Redo")) { editor.redo(); viewer.applyView(); }
  ImGui::SameLine();
  ImGui::Text("picked: %zu", editor.picked().size());
  static const char* groups[] = {"trunk", "head", "right_arm", "left_arm", "right_leg", "left_leg"};
  ImGui::SetNextItemWidth(130);
  ImGui::Combo("##group", &groupChoice_, groups, 6);
  ImGui::SameLine();
  if (ImGui::Button("Pick group")) {
    try {
      editor.pick(editor.groupVertices(groups[groupChoice_]), ImGui::GetIO().KeyShift);
    } catch (const std::exception& e) {
      viewer.status(e.what());
    }
  }
  if (ImGui::Button("Fix picked") && !editor.picked().empty()) {
    editor.addPickedSelection("fixed " + std::to_string(editor.pose().selections.size() + 1), true);
    editor.clearPicked();
  }
  ImGui::SameLine();
  if (ImGui::Button("Move picked") && !editor.picked().empty()) {
    editor.addPickedSelection("moving " + std::to_string(editor.pose().selections.size() + 1), false);
    editor.clearPicked();
  }
  ImGui::SameLine();
  if (ImGui::Button("Clear")) editor.clearPicked();
  if (const std::size_t compiled = editor.ownSelectionsAt(); compiled > 0)
    ImGui::TextDisabled("%zu selections compiled from the joints", compiled);
  for (std::size_t k = 0; k < editor.pose().selections.size(); ++k) {
    const PoseSelection& s = editor.pose().selections[k];
    ImGui::PushID(int(k));
    if (!s.fixed) {
      if (ImGui::RadioButton("##active", editor.state().active == int(k))) editor.setActive(int(k));
      ImGui::SameLine();
    }
    ImGui::Text("%s %s", s.fixed ? "[fixed]" : "[moving]", s.name.c_str());
    ImGui::SameLine();
    if (ImGui::SmallButton("x")) editor.removeSelection(int(k));
    ImGui::PopID();
  }
  if (editor.state().active >= 0) {
    const PoseTransform& t = editor.pose().selections[std::size_t(editor.state().active)].transform;
    ImGui::Text("rotation %.1f deg about (%.2f %.2f %.2f)", t.angleDeg, t.axis.x(), t.axis.y(), t.axis.z());
    ImGui::Text("translation %.1f %.1f %.1f mm", t.translation.x(), t.translation.y(), t.translation.z());
    ImGui::SetNextItemWidth(80);
    ImGui::InputFloat("step deg", &rotateStep_);
    for (int a = 0; a < 3; ++a) {
      ImGui::PushID(a + 100);
      const char axes[] = "xyz";
      if (ImGui::SmallButton(("-" + std::string(1, axes[a])).c_str())) editor.rotateActive(Eigen::Vector3d::Unit(a), -rotateStep_);
      ImGui::SameLine();
      if (ImGui::SmallButton(("+" + std::string(1, axes[a])).c_str())) editor.rotateActive(Eigen::Vector3d::Unit(a), rotateStep_);
      ImGui::PopID();
      if (a < 2) ImGui::SameLine();
    }
  }
  if (ImGui::Checkbox("ARAP", &arapOn_) || ImGui::SliderInt("iterations", &arapIterations_, 1, 30))
    editor.setArapIterations(arapOn_ ? std::max(1, arapIterations_) : 0);
  ImGui::InputText("pose file", posePath_, sizeof posePath_);
  if (ImGui::Button("Save pose")) {
    try { viewer.savePose(posePath_); } catch (const std::exception& e) { viewer.status(e.what()); }
  }
  ImGui::SameLine();
  if (ImGui::Button("Load pose")) {
    try { viewer.loadPose(posePath_); } catch (const std::exception& e) { viewer.status(e.what()); }
  }
}

void Panels::viewPanel(Viewer& viewer) {
  Overlays& overlays = viewer.overlays();
  ImGui::Checkbox("cage", &overlays.cage);
  ImGui::SameLine();
  ImGui::Checkbox("envelope", &overlays.envelope);
  ImGui::SameLine();
  ImGui::Checkbox("TM", &overlays.tm);
  if (ImGui::Button("Fit (F)")) viewer.fitCamera();
  ImGui::SameLine();
  if (ImGui::Button("Reset (R)")) viewer.resetCamera();
  ImGui::SetNextItemWidth(120);
  ImGui::SliderFloat("drag resolution", &interactiveScale_, 0.25f, 1.0f, "%.2f");
  if (ImGui::Checkbox("smooth shading", &smoothShading_)) viewer.redraw();
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("off: each voxel face lit with its own normal");
  CutControls& cuts = viewer.cuts();
  bool cutChanged = false;
  const char* names[3] = {"x cut", "y cut", "z cut"};
  for (int a = 0; a < 3; ++a) {
    ImGui::PushID(a + 200);
    cutChanged |= ImGui::Checkbox(names[a], &cuts.on[a]);
    ImGui::SameLine();
    cutChanged |= ImGui::Checkbox(">", &cuts.above[a]);
    ImGui::SameLine();
    ImGui::SetNextItemWidth(150);
    cutChanged |= ImGui::SliderFloat("mm", &cuts.at[a], float(cuts.lo()[a]), float(cuts.hi()[a]), "%.0f");
    ImGui::PopID();
  }
  cutChanged |= ImGui::Checkbox("free plane", &cuts.freeOn);
  if (cuts.freeOn) {
    cutChanged |= ImGui::SliderFloat3("normal", cuts.freeNormal, -1.0f, 1.0f);
    cutChanged |= ImGui::SliderFloat("offset", &cuts.freeOffset, -2000.0f, 2000.0f, "%.0f");
    if (std::abs(cuts.freeNormal[0]) + std::abs(cuts.freeNormal[1]) + std::abs(cuts.freeNormal[2]) == 0.0f) cuts.freeNormal[0] = 1.0f;
  }
  if (cutChanged) cuts.commit(viewer.editor());
}

void Panels::figuresPanel(Viewer& viewer) {
  const PoseEditor& editor = viewer.editor();
  const PoseFigures& f = editor.figures();
  const double voxelMm3 = viewer.grid().geometry().voxelVolume();
  double rest = 0, now = 0, restMass = 0, nowMass = 0;
  for (std::size_t l = 1; l < f.restVoxels.size(); ++l) {
    rest += f.restVoxels[l];
    now += f.deformedVoxels[l];
    const Organ* o = editor.organs() ? editor.organs()->find(int(l)) : nullptr;
    const double density = o ? o->density : 1.0;
    restMass += f.restVoxels[l] * voxelMm3 * density * 1e-3;
    nowMass += f.deformedVoxels[l] * voxelMm3 * density * 1e-3;
  }
  ImGui::Text("whole body: volume %+.3f %%, mass %+.3f %%", rest > 0 ? 100.0 * (now / rest - 1.0) : 0.0,
              restMass > 0 ? 100.0 * (nowMass / restMass - 1.0) : 0.0);
  ImGui::Text("TM vertices outside the cage: %zu", f.tmOutsideCage);
  ImGui::Text("inverted TM tets: %zu", f.tmInverted);
  const FrameTimes& t = viewer.frameTimes();
  ImGui::Text("frame %.1f ms, UI %.1f, present %.1f", t.totalMs, t.uiMs, t.presentMs);
  ImGui::Text("last deformation %.1f ms, ray cast %.1f ms (%dx%d)", t.deformMs, t.raycastMs, t.renderWidth, t.renderHeight);
}

void Panels::organsPanel(Viewer& viewer) {
  PoseEditor& editor = viewer.editor();
  const PoseFigures& f = editor.figures();
  const double voxelMm3 = viewer.grid().geometry().voxelVolume();
  const Palette& palette = viewer.palette();
  const auto lowered = [](std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
  };
  ImGui::InputText("search", organFilter_, sizeof organFilter_);
  const std::string filter = lowered(organFilter_);
  ImGui::BeginChild("organs", ImVec2(0, 0), true);
  if (ImGui::BeginTable("organ table", 4, ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit)) {
    ImGui::TableSetupColumn("show");
    ImGui::TableSetupColumn("organ", ImGuiTableColumnFlags_WidthStretch);
    ImGui::TableSetupColumn("mass g");
    ImGui::TableSetupColumn("change");
    ImGui::TableHeadersRow();
    for (std::size_t l = 1; l < f.restVoxels.size() && l < palette.size(); ++l) {
      if (f.restVoxels[l] <= 0.0) continue;
      const Organ* o = editor.organs() ? editor.organs()->find(int(l)) : nullptr;
      const std::string name = o ? o->name : "label " + std::to_string(l);
      if (!filter.empty() && lowered(name).find(filter) == std::string::npos) continue;
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      bool visible = palette.visible(Label(l));
      ImGui::PushID(int(l));
      if (ImGui::Checkbox("##v", &visible)) {
        std::vector<Label> hidden = editor.state().hidden;
        if (visible) hidden.erase(std::remove(hidden.begin(), hidden.end(), Label(l)), hidden.end());
        else hidden.push_back(Label(l));
        editor.setHidden(hidden);
        viewer.applyView();
      }
      ImGui::PopID();
      ImGui::TableNextColumn();
      const Rgb c = palette.color(Label(l));
      ImGui::TextColored(ImVec4(c.r / 255.f, c.g / 255.f, c.b / 255.f, 1.f), "%s", name.c_str());
      ImGui::TableNextColumn();
      const double density = o ? o->density : 1.0;
      ImGui::Text("%.1f", f.deformedVoxels[l] * voxelMm3 * density * 1e-3);
      ImGui::TableNextColumn();
      const double change = 100.0 * (f.deformedVoxels[l] / f.restVoxels[l] - 1.0);
      ImGui::TextColored(std::abs(change) > 3.0 ? ImVec4(1, 0.4f, 0.3f, 1) : ImVec4(0.8f, 0.8f, 0.8f, 1), "%+.2f%%", change);
    }
    ImGui::EndTable();
  }
  ImGui::EndChild();
}

void Panels::exportBox(Viewer& viewer, int fw, int fh) {
  // Export and status, bottom right.
  ExportJob& job = viewer.exportJob();
  ImGui::SetNextWindowPos(ImVec2(float(fw) - 10.0f, float(fh) - 10.0f), ImGuiCond_Always, ImVec2(1, 1));
  ImGui::Begin("export", nullptr, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoMove);
  ImGui::SetNextItemWidth(220);
  ImGui::InputText("##out", exportPath_, sizeof exportPath_);
  ImGui::SameLine();
  ImGui::Checkbox("preserve volumes", &exportPreserve_);
  if (job.running()) {
    ImGui::ProgressBar(float(job.fraction()), ImVec2(220, 0), job.stage().c_str());
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) job.cancel();
  } else if (ImGui::Button("Export posed grid")) {
    const std::string out = exportPath_;
    const std::string stem = out.substr(0, out.find('.'));
    viewer.startExport(out, stem + "_report.json", stem + ".png", exportPreserve_);
  }
  if (!job.running() && !job.message().empty()) ImGui::TextUnformatted(job.message().c_str());
  if (!viewer.statusText().empty()) ImGui::TextUnformatted(viewer.statusText().c_str());
  ImGui::End();
}

}  // namespace vox::app
