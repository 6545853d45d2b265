#include "app/viewer/joints_panel.h"

#include "app/viewer/viewer_app.h"
#include "geometry/deform/pose/pose_editor.h"
#include "geometry/skeleton/joints.h"

#include <imgui.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace vox::app {

void JointsPanel::draw(Viewer& viewer) {
  PoseEditor& editor = viewer.editor();
  if (!editor.turnsJoints()) {
    ImGui::TextWrapped("Open a joint pose (view --pose *_joints.json, with --organs) to turn the skeleton's joints.");
    return;
  }
  ImGui::BeginChild("joints", ImVec2(0, 250), true);
  for (const skeleton::Joint& joint : editor.joints()) {
    const skeleton::JointKind& kind = joint.kind();
    const int id = int(joint.id);
    ImGui::PushID(id);
    std::string label = kind.name;
    for (int d = 0; d < skeleton::kDofCount; ++d)
      if (const double a = editor.jointAngle(id, d); kind.dofNames[std::size_t(d)] && a != 0.0) {
        char angle[64];
        std::snprintf(angle, sizeof angle, "  %s %.1f", kind.dofNames[std::size_t(d)], a);
        label += angle;
      }
    const bool selected = editor.state().joint == id;
    if (ImGui::Selectable(label.c_str(), selected)) editor.selectJoint(selected ? -1 : id);
    if (selected && scrolledTo_ != id) ImGui::SetScrollHereY(0.0f);  // selected elsewhere (the script, undo): shown
    ImGui::Indent();
    for (int d = 0; d < skeleton::kDofCount; ++d) {
      const char* dof = kind.dofNames[std::size_t(d)];
      if (!dof) continue;
      const auto& range = kind.range[std::size_t(d)];
      float value = float(editor.jointAngle(id, d));
      const int key = id * skeleton::kDofCount + d;
      ImGui::SetNextItemWidth(170);
      if (ImGui::SliderFloat(dof, &value, float(range[0]), float(range[1]), "%.1f deg", ImGuiSliderFlags_AlwaysClamp)) {
        // Tenths of a degree, so that a saved pose reads as typed.
        editor.setJointAngle(id, d, std::round(double(value) * 10.0) / 10.0, sliding_ == key);
        sliding_ = key;
      }
      if (sliding_ == key && !ImGui::IsItemActive()) sliding_ = -1;
    }
    ImGui::Unindent();
    ImGui::PopID();
  }
  scrolledTo_ = editor.state().joint;
  ImGui::EndChild();
  // The joints on the articulated mesh (deform --articulated's solve), and
  // its steps from rest to the posed mesh.
  ArticulatedView& articulated = viewer.articulated();
  if (articulated.running()) {
    ImGui::Text("Articulated: step %d of %d", articulated.stepsDone(), articulated.stepCount());
    ImGui::SameLine();
    if (ImGui::Button("Cancel##articulated")) articulated.cancel();
  } else if (ImGui::Button("Solve on the articulated mesh")) {
    viewer.startArticulated();
  }
  if (articulated.held()) {
    if (articulated.shows(editor.pose().joints) || !articulated.shown()) {
      if (ImGui::Checkbox("Show the articulated steps", &articulated.shown())) viewer.redraw();
      ImGui::SetNextItemWidth(170);
      if (articulated.shown() && ImGui::SliderInt("step", &articulated.step(), 1, articulated.steps(), "%d", ImGuiSliderFlags_AlwaysClamp))
        viewer.redraw();
    } else {
      ImGui::TextWrapped("The joints changed since the articulated solve: solve again to see their steps.");
    }
  }
  // What an export of this pose is refused for, while it lasts.
  if (const auto& fault = editor.figures().bonesThroughEachOther) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.35f, 0.3f, 1.0f));
    ImGui::TextWrapped("%s", (*fault + "; an export is refused").c_str());
    ImGui::PopStyleColor();
  }
}

}  // namespace vox::app
