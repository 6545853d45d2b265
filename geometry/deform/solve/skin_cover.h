#pragma once
// Skin over the tissue a pose lays bare.
//
// A voxel phantom at rest has no skin where two parts touch (the arm
// against the trunk, the hand on the thigh, the back of the knee), and a
// thin skin resampled across 8 mm slices loses voxels where a limb turns
// across them. A pose that parts the limbs or turns them leaves inner tissue
// facing the air, which a dose calculation would treat as tissue without
// its skin. The cover gives it the skin it would have:
//  - a voxel of G' is bare when its label is neither background nor skin,
//    it faces background across one of its six faces (or the grid's
//    border), and no skin voxel lies in its 3 x 3 x 3 neighbourhood (the
//    measure of tests/bench/exposed_tissue.py);
//  - a bare voxel is mapped back to the source through the deformed tet
//    that holds its centre (as the rasterizer does); it is covered unless
//    one of the 8 source voxels about that point was itself bare at rest
//    (the phantom's own exposed tissue stays as it was, also where the
//    resampling shifts it by a voxel: a pose that moves nothing gives the
//    rest grid back);
//  - covering relabels a soft-tissue voxel to the skin label most frequent
//    in the smallest cube about it that holds skin (up to kSkinSearchVoxels
//    voxels away; else the most frequent skin label of G');
//  - a bone voxel that faces background, skin near it or not, is mapped back
//    the same way; unless a source voxel about it faced background too, it keeps
//    its label (a rigid bone keeps its voxels) and the background across its
//    faces takes that skin label instead, a skin laid over the bone.
// The cover moves volume from the tissues under the skin to the skin; the
// result counts it per label. Deterministic, independent of the threads.

#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

inline constexpr int kSkinSearchVoxels = 6;
// The report warns when the cover adds more than this share of a skin
// label's rest voxels to it.
inline constexpr double kSkinCoverWarnPercent = 3.0;

struct SkinCover {
  std::uint64_t bareVoxels = 0;       // bare voxels and bone voxels facing background in G' before the cover
  std::uint64_t bareAtRest = 0;       // of them: so at rest too, left as they are
  std::uint64_t boneVoxels = 0;       // of them: bone the pose bared, kept, with skin laid over them
  std::uint64_t covered = 0;          // relabelled to skin
  std::uint64_t overBone = 0;         // background voxels across the bare bone's faces made skin
  std::vector<std::uint64_t> from;    // covered voxels by their former label (index = label)
  std::vector<std::uint64_t> to;      // covered and over-bone voxels by the skin label they took (index = label)
};

// The bare voxels of `grid` (above), as a flag per voxel (x fastest).
// skin and bone: flags per label (index = label; labels beyond them count as
// neither).
std::vector<std::uint8_t> bareVoxels(const LabelGrid& grid, std::span<const std::uint8_t> skin, int threads = 0);

// Covers the bare voxels of `posed` (G' rasterized from `source` through
// rest -> deformed) that were not bare in `source`. Throws InputError when
// posed's geometry is not the output grid of this deformation. Does nothing
// when `skin` flags no label.
SkinCover coverBareTissue(LabelGrid& posed, const LabelGrid& source, const TetMesh& rest,
                          const std::vector<Eigen::Vector3d>& deformed, std::span<const std::uint8_t> skin,
                          std::span<const std::uint8_t> bone, int threads = 0);

}  // namespace vox
