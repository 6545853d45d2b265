#pragma once
// Closed test cages for the deformation suites.

#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <random>
#include <vector>

namespace vox::test {

// Unit icosphere: subdivided icosahedron projected to the sphere, outward
// counter-clockwise faces. 12, 42, 162, 642 vertices for 0..3 subdivisions.
TriMesh icosphere(int subdivisions);

// A non-convex, star-shaped cage: the icosphere with every vertex pushed to
// radius r(u) = radius * (1 + bump * sin(3 u_x) cos(2 u_z)) along its direction u,
// then translated to `center`.
TriMesh bumpyCage(int subdivisions, double radius, double bump, const Eigen::Vector3d& center);

// Closed box surface around [lo, hi], each side split into n[axis] segments.
TriMesh subdividedBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3i& n);

// Closed surface of a union of unit cubes (integer cell coordinates), each
// boundary square split into two triangles. Cells must not touch along an
// edge or a vertex only.
TriMesh voxelShapeCage(const std::vector<Eigen::Vector3i>& cells);

// Random points strictly inside `cage` (winding number > 1/2), at least
// `clearance` away from every cage face.
std::vector<Eigen::Vector3d> randomInteriorPoints(const TriMesh& cage, int count, double clearance, std::mt19937& rng);

// Distance from p to the triangle (a, b, c).
double pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c);

}  // namespace vox::test
