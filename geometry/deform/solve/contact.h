#pragma once
// Contact of a posed tet mesh with itself: the places where its boundary
// (the skin, and the faces a cut opened) has passed into tissue it lay
// apart from at rest, as in a crease that a joint's turn closes (the back
// of the knee against the thigh, the front of the thigh against the belly).
// Each such boundary vertex gets the nearest point of the boundary it
// crossed, which a solve then uses as its target (the two sides meet on a
// contact surface instead of overlapping); so can a boundary face's
// centroid, for surfaces that cross between their vertices.
//
// "Apart at rest": every vertex of the tet it lies in is farther than
// restSeparationMm from it at rest, or on another side (ContactOptions::
// side). A tet's own neighbourhood never counts, however it turned, nor do
// the two coincident sides of a cut without sides.

#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

struct ContactOptions {
  double restSeparationMm = 20.0;
  // A vertex counts as through the other side only this far (mm) from its
  // boundary: one that merely touches it is in contact, not through it.
  double toleranceMm = 0.1;
  // The boundary crossed is searched this far (mm) from the vertex.
  double searchMm = 60.0;
  // Per vertex, a side (the limb group its tets lie in; -1: several, or
  // none), or empty. Two vertices of two sides lay apart at rest whatever
  // their distance: the two faces of a limb cut, coincident at rest, press
  // into each other where a crease closes (the back of the thigh against
  // the buttock, the arm against the chest's side).
  std::vector<std::int32_t> side;
  // Also the centroids of the boundary faces whose three vertices are
  // candidates: two sides' surfaces that cross between their vertices
  // (each vertex outside the tissue across) overlap in a lens no vertex
  // lies in.
  bool faceCentroids = false;
};

struct Penetration {
  std::int32_t vertex = -1;     // -1: a face's centroid (faceCentroids)
  std::array<std::int32_t, 3> of{-1, -1, -1};  // the vertices it moves: `vertex` (then -1, -1), or the face's
  Eigen::Vector3d at = Eigen::Vector3d::Zero();  // where it lies: the vertex, or the face's centroid
  std::int32_t tet = -1;        // a tet it lies in
  Eigen::Vector3d surface = Eigen::Vector3d::Zero();  // the nearest point of the boundary apart from it at rest
  std::array<std::int32_t, 3> face{};  // that point's boundary face
  double depth = 0.0;           // |surface - position|
};

// The boundary faces of `tets` (faces of one tet only), oriented outwards.
std::vector<std::array<std::int32_t, 3>> boundaryFaces(std::span<const Tet> tets, std::size_t vertexCount);

// The vertices v with candidate[v] that lie on the boundary of `tets` and,
// posed at `positions`, inside a tet t with penetrable[t] that they lay
// apart from at `rest`; each with the nearest point of a boundary face of
// a penetrable tet whose three vertices all lay apart from it at rest.
// Sorted by vertex, then the faces' centroids (faceCentroids) in the order
// of the boundary; deterministic.
std::vector<Penetration> findPenetrations(std::span<const Eigen::Vector3d> rest, std::span<const Tet> tets,
                                          std::span<const Eigen::Vector3d> positions, std::span<const std::uint8_t> candidate,
                                          std::span<const std::uint8_t> penetrable, const ContactOptions& options = {});

}  // namespace vox
