#pragma once
// SparseCholesky: factorize a sparse symmetric positive definite matrix once,
// then solve for as many right-hand sides as needed (the per-frame path of the
// cage ARAP and the propagation solver). CHOLMOD does the work when SuiteSparse
// is available at build time; Eigen's SimplicialLDLT otherwise. Which one is
// compiled in is decided in sparse_cholesky.cpp only.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>

namespace vox {

class SparseCholesky {
public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(SparseCholesky&&) noexcept;
  SparseCholesky& operator=(SparseCholesky&&) noexcept;

  // A: n by n, symmetric positive definite. Only the lower triangle (row >=
  // column) is read. Throws RuntimeFailure when A is not positive definite
  // (a singular system: some unknowns are not tied to any constraint).
  void factorize(const Eigen::SparseMatrix<double>& A);

  // B: n by k right-hand sides. Returns X (n by k) with A X = B.
  // Not thread-safe: the backend keeps a workspace.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& B) const;

  Eigen::Index size() const { return n_; }
  bool factorized() const { return factorized_; }

  // "CHOLMOD" or "Eigen SimplicialLDLT".
  static const char* backendName();

private:
  struct Backend;
  std::unique_ptr<Backend> backend_;
  Eigen::Index n_ = 0;
  bool factorized_ = false;
};

}  // namespace vox
