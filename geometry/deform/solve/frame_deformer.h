#pragma once
// FrameDeformer: the per-frame path of the interactive deformation (thesis
// 3.2.3 and 4.2.2), chaining
//   cage ARAP (handle targets -> deformed cage)
//   -> Green coordinates to the envelope vertices and to the transfer-mesh
//      (TM) vertices inside the cage (two dense products)
//   -> rigidity propagation for the TM vertices outside the cage
//   -> envelope vertices outside the cage (possible with inset cages), carried
//      by the deformed TM tet they were attached to at rest.
// Everything that does not depend on the handle targets is done once in
// precompute(): coordinates, the ARAP factorization, the propagation
// factorizations, the envelope-to-TM attachment. Per frame, the TM product
// runs on all cores, then the envelope product (memory bound) and the
// propagation solves (compute bound) share them.

#include "geometry/deform/solve/cage_arap.h"
#include "geometry/deform/solve/green_coordinates.h"
#include "geometry/deform/solve/propagation.h"
#include "geometry/deform/solve/rigid_bones.h"
#include "geometry/tet_mesh.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

struct FrameDeformerOptions {
  // Storage of the Green coordinates used every frame. The two products are
  // the bulk of a frame and are bound by memory bandwidth, so their time
  // follows the bytes per coefficient. Errors, relative to the cage
  // displacement (greenCageDisplacement): Double ~1e-15, Float ~1e-8, Half
  // ~2e-5 (measured on random interior points; larger near the cage). The
  // rest pose is reproduced exactly in every precision. Half is meant for
  // the interactive viewer, Float or Double for results that are written out.
  GreenPrecision precision = GreenPrecision::Float;
  // Per TM vertex (empty: none): 1 to place the vertex by the propagation
  // even when it lies inside the cage (a limb's vertex in the part of an
  // inset cage that belongs to the body beside it).
  std::vector<std::uint8_t> propagateAnyway;
  // Per TM vertex (empty: none): its rigid bone group (rigid_bones.h) or -1.
  // Each group moves rigidly with the fit to its Green-coordinate positions,
  // and the propagation takes its vertices as known.
  std::vector<std::int32_t> rigidGroups;
  // The vertices within this many TM edge rings of a rigid group's
  // vertices (and none of them) are placed by the propagation, from the
  // rigid bones and the Green-coordinate vertices beyond: the soft tissue
  // around a bone follows the bone instead of tearing from it.
  int rigidBandRings = 2;
};

// Milliseconds spent in each stage of the last update().
struct FrameTimings {
  double arap = 0;
  double greenTransferMesh = 0;   // TM vertices inside the cage
  double greenEnvelope = 0;       // envelope vertices inside the cage, with the propagation running beside it
  double rigidBones = 0;          // the rigid fit of the bone groups
  double propagation = 0;         // eq. 4.3-4.4 alone (part of greenEnvelope's time)
  double envelopeOutside = 0;     // envelope vertices carried by the TM
  double total = 0;
};

struct FrameDeformerStats {
  std::size_t envelopeInside = 0, envelopeOutside = 0;
  std::size_t transferMeshInside = 0, transferMeshOutside = 0;
  PropagationDiagnostics propagation;
  std::size_t rigidGroups = 0, rigidVertices = 0, rigidGroupsDropped = 0;
  // precompute() stages, milliseconds.
  double classifyMs = 0, greenEnvelopeMs = 0, greenTransferMeshMs = 0, arapFactorMs = 0, propagationFactorMs = 0,
         attachMs = 0;
};

class FrameDeformer {
public:
  // cage: closed, outward oriented (#C vertices). envelope: #E points (may
  // be empty). transferMesh: rest TM with positive tets (may be empty when
  // every envelope vertex is inside the cage). handles: cage vertex ids
  // (CageArap::precompute). Throws InputError for an open cage, a
  // handle-less cage component, envelope vertices outside the cage with no
  // TM to carry them, or TM vertices outside the cage with no tet inside it.
  void precompute(const TriMesh& cage, std::span<const Eigen::Vector3d> envelope, const TetMesh& transferMesh,
                  std::span<const std::int32_t> handles, const FrameDeformerOptions& options = {});

  // A new handle set on the same cage (refactorizes the ARAP system only).
  void setHandles(std::span<const std::int32_t> handles);

  // One frame. handleTargets: #handles by 3 (handles order). Runs
  // `arapIterations` ARAP iterations warm-started from the previous frame.
  // Handle targets at their rest positions give the rest pose exactly.
  // rigidMotions: per rigid bone group (options.rigidGroups ids), the motion
  // its vertices take; empty: each group's fit to its Green-coordinate
  // positions.
  void update(const Eigen::MatrixX3d& handleTargets, int arapIterations, std::span<const Eigen::Isometry3d> rigidMotions = {});

  const std::vector<Eigen::Vector3d>& cagePositions() const { return arap_.positions(); }
  const std::vector<Eigen::Vector3d>& envelopePositions() const { return envelope_; }
  const std::vector<Eigen::Vector3d>& transferMeshPositions() const { return transferMesh_; }
  // #TM vertices: 1 when inside the cage (placed by Green coordinates).
  const std::vector<std::uint8_t>& transferMeshInside() const { return tmInside_; }
  const std::vector<std::uint8_t>& envelopeInside() const { return envelopeInside_; }
  const std::vector<std::int32_t>& handles() const { return arap_.handles(); }
  const FrameTimings& timings() const { return timings_; }
  const FrameDeformerStats& stats() const { return stats_; }
  const CageArap& arap() const { return arap_; }

private:
  TriMesh restCage_;
  CageArap arap_;
  GreenCoordinates envelopeGreen_, tmGreen_;
  std::vector<std::int32_t> envelopeInsideIds_, tmInsideIds_;
  std::vector<Eigen::Vector3d> envelopeInsideRest_, tmInsideRest_;
  std::vector<std::uint8_t> envelopeInside_, tmInside_;
  RigidityPropagation propagation_;
  RigidBoneFit rigidBones_;
  // Envelope vertices outside the cage: vertex, TM tet, barycentric weights.
  struct Attachment {
    std::int32_t vertex;
    Tet tet;
    Eigen::Vector4d weights;
  };
  std::vector<Attachment> attachments_;

  std::vector<Eigen::Vector3d> restEnvelope_, restTransferMesh_;
  std::vector<Eigen::Vector3d> envelope_, transferMesh_, envelopeScratch_, tmScratch_;
  FrameTimings timings_;
  FrameDeformerStats stats_;
};

}  // namespace vox
