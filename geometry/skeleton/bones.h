#pragma once
// Bones of an organ table: which labels are bones, and which bone.
//
// The ICRP 110 tables name each bone by its first comma-separated words
// ("Humeri, upper half, cortical", "Ulnae and radii, spongiosa", "Tibiae,
// fibulae and patellae, cortical", "Cervical spine, cortical", "Pelvis,
// spongiosa"); the words after the first comma say which part of the bone
// or side ("Kidney, left, pelvis" is a kidney, not a bone). Limb bones are
// named without a side in those tables; the skeleton (body_parts.h) splits
// them by geometry. A side in the name ("Humerus, right") is kept.

#include "geometry/label_grid.h"
#include "geometry/organ_table.h"

#include <cstdint>
#include <string>
#include <vector>

namespace vox::skeleton {

enum class Bone : std::uint8_t {
  None = 0,
  Cranium,
  Mandible,
  CervicalSpine,
  ThoracicSpine,
  LumbarSpine,
  Sacrum,
  Pelvis,  // os coxae
  Ribs,
  Sternum,
  Clavicle,
  Scapula,
  Humerus,
  ForearmBones,  // ulna and radius
  HandBones,     // wrist and hand
  Femur,
  LowerLegBones,  // tibia, fibula, patella
  FootBones,      // ankle and foot
};
inline constexpr int kBoneCount = 17;

enum class Side : std::uint8_t { Axial = 0, Right = 1, Left = 2 };

// "cranium", "cervical_spine", "humerus", "forearm_bones", ... (snake case).
const char* boneName(Bone bone);
const char* sideName(Side side);  // "axial", "right", "left"
// Limb and girdle bones come in pairs (split left/right); the others lie on
// the midline.
bool isPaired(Bone bone);

// The bone an organ name describes (Bone::None for soft tissue), from its
// first comma-separated words, case-insensitive.
Bone classifyBone(const std::string& organName);
// The side an organ name states by the words "left" / "right" (Axial when
// neither or both).
Side sideInName(const std::string& organName);

// Per label of `organs` (index = label, up to maxLabel): its bone.
std::vector<Bone> boneOfLabels(const OrganTable& organs, Label maxLabel);

// Whether an organ is skin: its name's first word is "Skin" (any case).
bool isSkin(const std::string& organName);
// Per label of `organs` (index = label, up to maxLabel): 1 for skin.
std::vector<std::uint8_t> skinOfLabels(const OrganTable& organs, Label maxLabel);
// True when the table names at least one bone.
bool namesBones(const OrganTable& organs);
// Throws InputError(source, ...) for a table that names no bone, with the
// names the classification looks for.
void requireBones(const OrganTable& organs, const std::string& source);

}  // namespace vox::skeleton
