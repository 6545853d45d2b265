#pragma once
// Green coordinates (Lipman, Levin, Cohen-Or 2008; thesis eq. 3.3-3.4).
//
// A point eta inside a closed cage P = (V, T) with outward normals n_j is
//   eta = sum_i phi_i(eta) v_i + sum_j psi_j(eta) n(t_j),
// and the deformation induced by the deformed cage P' is
//   eta' = sum_i phi_i(eta) v'_i + sum_j psi_j(eta) s_j n(t'_j)
// with s_j the stretch factor of face j (greenStretchFactors).
//
// phi and psi are the boundary integrals of Green's third identity applied to
// the linear function x -> x:
//   psi_j(eta)      = 1/(4 pi) int_{t_j} 1 / |xi - eta| dA            (the paper's -I)
//   phi_i(eta)      = sum_{j ni i} 1/(4 pi) int_{t_j} Gamma_i(xi) n_j.(xi - eta) / |xi - eta|^3 dA
// with Gamma_i the hat function of vertex i on t_j. The paper evaluates them
// with GCTriInt (angles by arccos, log of (1 - cos)^2): these lose digits
// when eta projects near an edge or vertex of a face or lies near a face plane.
// This implementation evaluates the same closed-form integrals through the
// equivalent edge decomposition (Gauss-Green on the face plane): per edge the
// line integral L = int ds / |xi - eta| written without cancellation (log1p
// of a difference computed from its factored form, the d^2/(R - l) branch on
// the far side), per face the signed solid angle by the van Oosterom-Strackee
// atan2 formula, its triple product from the height over the face plane
// taken at the nearest face vertex, and recomputed in long double from exact
// differences where the point is close to a face side. Measured reproduction
// error (|sum phi v + sum psi n - eta| / cage size): ~5e-15 deep inside and at
// 1e-9 cage sizes from a face or a vertex, 1e-12 at 1e-9 from an edge.
//
// Coordinates are only meaningful for points strictly inside the cage; use
// cageWindingNumber / insideCage to classify points first.

#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

// Storage precision of the coordinate matrix. The per-frame product reads
// the whole matrix every frame and is bound by memory bandwidth, so its time
// scales with the bytes per coefficient (8, 4, 2). Applied in displacement
// form (greenCageDisplacement), the error is a fraction of the cage
// displacement: on random interior points 1.3e-8 of it for Float and 2.2e-5
// for Half (IEEE binary16, 11-bit significand), more near the cage's faces
// (GreenCoordinates.DisplacementFormInEveryPrecision asserts 1e-6 and 2e-3).
// Half is for interactive display, not for the final rasterization.
enum class GreenPrecision { Double, Float, Half };

// Row p holds the coordinates of point p: phi (#V columns, one per cage
// vertex), then psi (#F columns, one per cage face), then zero padding so that
// the row length is a multiple of kGreenColumnBlock.
class GreenCoordinates {
public:
  static constexpr Eigen::Index kGreenColumnBlock = 16;

  GreenCoordinates() = default;

  Eigen::Index pointCount() const { return rows_; }
  std::int32_t cageVertexCount() const { return cageVertices_; }
  std::int32_t cageFaceCount() const { return cageFaces_; }
  Eigen::Index stride() const { return stride_; }
  GreenPrecision precision() const { return precision_; }

  double phi(Eigen::Index point, std::int32_t vertex) const { return value(point, vertex); }
  double psi(Eigen::Index point, std::int32_t face) const { return value(point, cageVertices_ + face); }

  // Row-major #P by stride() matrices; only the one matching precision() is
  // non-empty.
  using MatrixD = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  using MatrixF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  using MatrixH = Eigen::Matrix<Eigen::half, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const MatrixD& coefficientsDouble() const { return d_; }
  const MatrixF& coefficientsFloat() const { return f_; }
  const MatrixH& coefficientsHalf() const { return h_; }

private:
  friend GreenCoordinates greenCoordinates(const TriMesh&, std::span<const Eigen::Vector3d>, GreenPrecision);
  double value(Eigen::Index r, Eigen::Index c) const {
    switch (precision_) {
      case GreenPrecision::Double: return d_(r, c);
      case GreenPrecision::Float: return double(f_(r, c));
      case GreenPrecision::Half: return double(float(h_(r, c)));
    }
    return 0.0;
  }

  Eigen::Index rows_ = 0;
  Eigen::Index stride_ = 0;
  std::int32_t cageVertices_ = 0;
  std::int32_t cageFaces_ = 0;
  GreenPrecision precision_ = GreenPrecision::Double;
  MatrixD d_;
  MatrixF f_;
  MatrixH h_;
};

// Green coordinates of `points` (#P) with respect to `cage` (closed, outward
// oriented). Runs on all hardware threads and reports progress as
// "green coordinates". Throws InputError("cage", ...) for an invalid cage.
GreenCoordinates greenCoordinates(const TriMesh& cage, std::span<const Eigen::Vector3d> points,
                                  GreenPrecision precision = GreenPrecision::Double);

// Stretch factors s_j of the paper (section 4, 3D): with u, v two edge vectors
// of face j at rest and u', v' deformed,
//   s_j = sqrt(|u'|^2 |v|^2 - 2 (u'.v')(u.v) + |v'|^2 |u|^2) / (sqrt(8) area(t_j)).
// s_j = 1 for a rigid motion of the face and k for a uniform scaling by k.
// Returns #F values. `deformed` holds #V positions.
Eigen::VectorXd greenStretchFactors(const TriMesh& restCage, std::span<const Eigen::Vector3d> deformed);

// What a deformed cage contributes to every point: the #V + #F rows
// [v'_i - c ; s_j n(t'_j)] (zero rows for the padding) and the offset c (the
// deformed cage's vertex centroid). Subtracting c makes float coordinates
// lose nothing to the cage's distance from the origin (sum_i phi_i = 1).
struct GreenCageFrame {
  Eigen::Matrix<double, Eigen::Dynamic, 3> rows;  // stride by 3
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
};
GreenCageFrame greenCageFrame(const TriMesh& restCage, std::span<const Eigen::Vector3d> deformed, Eigen::Index stride);

// greenCageFrame(deformed) minus greenCageFrame(rest cage). Applied on top of
// the points' rest positions (applyGreenCoordinates' `base`) it gives the
// same deformation, reproduces the rest cage bit for bit, and makes the
// error of float coordinates proportional to the cage displacement rather
// than to the cage size.
GreenCageFrame greenCageDisplacement(const TriMesh& restCage, std::span<const Eigen::Vector3d> deformed, Eigen::Index stride);

// out[p] = base[p] + sum_c coefficients(p, c) rows(c) + offset for every
// point (#P); base may be empty (zero). A dense product, bound by memory
// bandwidth; runs on every hardware thread.
void applyGreenCoordinates(const GreenCoordinates& coordinates, const GreenCageFrame& frame, std::span<Eigen::Vector3d> out,
                           std::span<const Eigen::Vector3d> base = {});
// The same for the points [begin, end) only, on the calling thread, for
// callers that schedule the product beside other work. out and base span all
// #P points.
void applyGreenCoordinateRows(const GreenCoordinates& coordinates, const GreenCageFrame& frame, std::size_t begin,
                              std::size_t end, std::span<Eigen::Vector3d> out, std::span<const Eigen::Vector3d> base = {});

// Convenience: deformed positions of the points of `coordinates` for the cage
// deformed to `deformed` (#V), stretch factors included.
std::vector<Eigen::Vector3d> greenDeform(const GreenCoordinates& coordinates, const TriMesh& restCage,
                                         std::span<const Eigen::Vector3d> deformed);

// Generalized winding number of a closed, outward oriented cage at p: the sum
// of the signed solid angles of its faces over 4 pi. 1 inside, 0 outside,
// 1/2 on a face.
double cageWindingNumber(const TriMesh& cage, const Eigen::Vector3d& p);

// inside[p] = 1 when the winding number of points[p] exceeds 1/2, 0
// otherwise. Robust for any closed cage, including points near its faces.
// Runs on all hardware threads.
std::vector<std::uint8_t> insideCage(const TriMesh& cage, std::span<const Eigen::Vector3d> points);

}  // namespace vox
