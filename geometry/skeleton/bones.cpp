#include "geometry/skeleton/bones.h"

#include "geometry/error.h"

#include <algorithm>
#include <array>
#include <cctype>

namespace vox::skeleton {

namespace {

constexpr std::array<const char*, kBoneCount + 1> kBoneNames = {
    "none",      "cranium", "mandible", "cervical_spine", "thoracic_spine", "lumbar_spine",
    "sacrum",    "pelvis",  "ribs",     "sternum",        "clavicle",       "scapula",
    "humerus",   "forearm_bones",       "hand_bones",     "femur",          "lower_leg_bones",
    "foot_bones"};

bool has(const std::vector<std::string>& words, const char* word) {
  return std::find(words.begin(), words.end(), word) != words.end();
}

}  // namespace

const char* boneName(Bone bone) {
  const int i = int(bone);
  return i >= 0 && i <= kBoneCount ? kBoneNames[std::size_t(i)] : "?";
}

const char* sideName(Side side) { return side == Side::Right ? "right" : side == Side::Left ? "left" : "axial"; }

bool isPaired(Bone bone) {
  switch (bone) {
    case Bone::Clavicle:
    case Bone::Scapula:
    case Bone::Humerus:
    case Bone::ForearmBones:
    case Bone::HandBones:
    case Bone::Femur:
    case Bone::LowerLegBones:
    case Bone::FootBones: return true;
    default: return false;
  }
}

Bone classifyBone(const std::string& organName) {
  // Only the words before the first comma name the structure.
  const std::vector<std::string> w = organNameWords(organName.substr(0, organName.find(',')));
  if (w.empty() || anyWordStartsWith(w, {"cartilage", "marrow", "muscle", "skin", "blood", "lymph"})) return Bone::None;
  if (has(w, "spine") || anyWordStartsWith(w, {"vertebra"})) {
    if (has(w, "cervical")) return Bone::CervicalSpine;
    if (has(w, "thoracic")) return Bone::ThoracicSpine;
    if (has(w, "lumbar")) return Bone::LumbarSpine;
    return Bone::None;
  }
  if (anyWordStartsWith(w, {"humer"})) return Bone::Humerus;
  if (anyWordStartsWith(w, {"ulna", "radius", "radii"})) return Bone::ForearmBones;
  if (anyWordStartsWith(w, {"wrist", "carp", "metacarp"}) || (anyWordStartsWith(w, {"hand"}) && anyWordStartsWith(w, {"bone"})))
    return Bone::HandBones;
  if (anyWordStartsWith(w, {"clavic"})) return Bone::Clavicle;
  if (anyWordStartsWith(w, {"scapul"})) return Bone::Scapula;
  if (anyWordStartsWith(w, {"femor", "femur"})) return Bone::Femur;
  if (anyWordStartsWith(w, {"tibia", "fibula", "patell"})) return Bone::LowerLegBones;
  if (anyWordStartsWith(w, {"ankle", "tars", "metatars", "calcane", "talus"}) ||
      ((has(w, "foot") || has(w, "feet")) && anyWordStartsWith(w, {"bone"})))
    return Bone::FootBones;
  if (anyWordStartsWith(w, {"crani", "skull"})) return Bone::Cranium;
  if (anyWordStartsWith(w, {"mandib"})) return Bone::Mandible;
  if (anyWordStartsWith(w, {"sacrum", "coccyx"})) return Bone::Sacrum;
  if (anyWordStartsWith(w, {"pelvis", "coxa", "ilium", "ischium", "pubis"})) return Bone::Pelvis;
  if (anyWordStartsWith(w, {"rib"})) return Bone::Ribs;
  if (anyWordStartsWith(w, {"stern"})) return Bone::Sternum;
  return Bone::None;
}

Side sideInName(const std::string& organName) {
  const std::vector<std::string> w = organNameWords(organName);
  const bool left = has(w, "left"), right = has(w, "right");
  if (left == right) return Side::Axial;
  return left ? Side::Left : Side::Right;
}

std::vector<Bone> boneOfLabels(const OrganTable& organs, Label maxLabel) {
  std::vector<Bone> bones(std::size_t(maxLabel) + 1, Bone::None);
  for (const auto& [id, organ] : organs.organs())
    if (id >= 1 && id <= int(maxLabel)) bones[std::size_t(id)] = classifyBone(organ.name);
  return bones;
}

bool isSkin(const std::string& organName) {
  std::string first;
  for (const unsigned char c : organName) {
    if (!std::isalpha(c)) break;
    first += char(std::tolower(c));
  }
  return first == "skin";
}

std::vector<std::uint8_t> skinOfLabels(const OrganTable& organs, Label maxLabel) {
  std::vector<std::uint8_t> skin(std::size_t(maxLabel) + 1, 0);
  for (const auto& [id, organ] : organs.organs())
    if (id >= 1 && id <= int(maxLabel)) skin[std::size_t(id)] = isSkin(organ.name);
  return skin;
}

bool namesBones(const OrganTable& organs) {
  return std::any_of(organs.organs().begin(), organs.organs().end(),
                     [](const auto& entry) { return classifyBone(entry.second.name) != Bone::None; });
}

void requireBones(const OrganTable& organs, const std::string& source) {
  if (!namesBones(organs))
    throw InputError(source, "the organ table names no bones (looked for humeri, ulnae and radii, hand bones, clavicles, "
                             "scapulae, femora, tibiae, foot bones, spine, sacrum, pelvis, cranium, mandible, ribs, sternum), "
                             "so the body parts and joints cannot be found");
}

}  // namespace vox::skeleton
