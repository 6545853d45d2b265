#pragma once
// Smooth models of the input's junctions (thesis 2.2.5), independent of the
// current mesh: each 2-junction (the facets between labels x < y) becomes a
// point set surface sampled at the input facets' centroids with area weights
// and normals pointing from x to y; each 1-junction (the feature edges of
// one label set) a moving least-squares line sampled at its edges. The
// smoothing projects boundary vertices back onto them, which removes the
// aliasing of voxel input (PSS) while keeping the vertices on their junction.

#include "geometry/remesh/label_set.h"
#include "geometry/remesh/remesh_complex.h"

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace vox::remesh {

class InterfaceSurfaces {
public:
  // Samples the junctions of `complex` (the hull's label -1 facets excluded).
  // `radius` is the width h of the Gaussian weights exp(-d^2 / h^2); samples
  // farther than 2 h are ignored.
  InterfaceSurfaces(const RemeshComplex& complex, double radius, bool hermite);

  // Adamson-Alexa projection of p onto the x|y surface (x < y), iterated:
  // weighted centroid and normal of the samples near p, then p onto that
  // plane. Only samples whose normal agrees with `normal` (oriented x to y)
  // count, so the two sides of a thin layer do not cancel. Returns false
  // (p unchanged) when no sample is in reach.
  bool projectOnSurface(std::int32_t x, std::int32_t y, const Eigen::Vector3d& normal, Eigen::Vector3d& p) const;
  // Projection of p onto the weighted least-squares line through the
  // samples of the 1-junction with label set `labels`.
  bool projectOnCurve(const LabelSet& labels, Eigen::Vector3d& p) const;

  double radius() const { return radius_; }
  std::size_t surfaceSamples() const { return surfaceIndex_.samples.size(); }
  std::size_t curveSamples() const { return curveIndex_.samples.size(); }

private:
  struct Sample {
    Eigen::Vector3f p;
    Eigen::Vector3f n;  // surface: unit normal; curve: unit direction
    float weight;
    std::int32_t id;    // surface or curve id
  };
  struct SpatialIndex {
    Eigen::Vector3d origin;
    double cell = 1.0;
    std::int64_t dims[3] = {1, 1, 1};
    std::vector<std::int64_t> start;  // CSR over cells
    std::vector<Sample> samples;      // sorted by cell, then by sampling order
    void build(std::vector<Sample> in, double cellSize);
    template <typename F>
    void near(const Eigen::Vector3d& p, const F& visit) const;
  };

  double radius_;
  bool hermite_;
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> surfaceIds_;
  std::map<std::vector<std::int32_t>, std::int32_t> curveIds_;
  SpatialIndex surfaceIndex_, curveIndex_;
};

}  // namespace vox::remesh
