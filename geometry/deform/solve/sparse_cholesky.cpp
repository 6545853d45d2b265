#include "geometry/deform/solve/sparse_cholesky.h"

#include "geometry/error.h"

#include <string>

#if __has_include(<cholmod.h>)
#define VOX_SPARSE_CHOLESKY_CHOLMOD 1
#include <cholmod.h>
#else
#include <Eigen/SparseCholesky>
#endif

namespace vox {

#if VOX_SPARSE_CHOLESKY_CHOLMOD

struct SparseCholesky::Backend {
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  // Workspace reused by cholmod_solve2 from one solve to the next.
  cholmod_dense* x = nullptr;
  cholmod_dense* y = nullptr;
  cholmod_dense* e = nullptr;

  Backend() {
    cholmod_start(&common);
    common.print = 0;  // failures are reported through exceptions, not stdout
  }
  ~Backend() {
    release();
    cholmod_finish(&common);
  }
  void release() {
    if (factor) cholmod_free_factor(&factor, &common);
    if (x) cholmod_free_dense(&x, &common);
    if (y) cholmod_free_dense(&y, &common);
    if (e) cholmod_free_dense(&e, &common);
  }

  void factorize(const Eigen::SparseMatrix<double>& a) {
    release();
    // A view of Eigen's compressed column storage; stype -1 makes CHOLMOD
    // read the lower triangle only.
    cholmod_sparse view{};
    view.nrow = std::size_t(a.rows());
    view.ncol = std::size_t(a.cols());
    view.nzmax = std::size_t(a.nonZeros());
    view.p = const_cast<int*>(a.outerIndexPtr());
    view.i = const_cast<int*>(a.innerIndexPtr());
    view.x = const_cast<double*>(a.valuePtr());
    view.stype = -1;
    view.itype = CHOLMOD_INT;
    view.xtype = CHOLMOD_REAL;
    view.dtype = CHOLMOD_DOUBLE;
    view.sorted = 1;
    view.packed = 1;
    factor = cholmod_analyze(&view, &common);
    if (!factor) throw RuntimeFailure("sparse Cholesky: CHOLMOD analysis failed (status " + std::to_string(common.status) + ")");
    const int ok = cholmod_factorize(&view, factor, &common);
    if (!ok || common.status == CHOLMOD_NOT_POSDEF || factor->minor < factor->n)
      throw RuntimeFailure("sparse Cholesky: matrix is not positive definite (pivot " + std::to_string(factor->minor) +
                           " of " + std::to_string(factor->n) + ")");
  }

  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) {
    cholmod_dense rhs{};
    rhs.nrow = std::size_t(b.rows());
    rhs.ncol = std::size_t(b.cols());
    rhs.nzmax = rhs.nrow * rhs.ncol;
    rhs.d = rhs.nrow;
    rhs.x = const_cast<double*>(b.data());
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    if (!cholmod_solve2(CHOLMOD_A, factor, &rhs, nullptr, &x, nullptr, &y, &e, &common))
      throw RuntimeFailure("sparse Cholesky: CHOLMOD solve failed (status " + std::to_string(common.status) + ")");
    Eigen::MatrixXd out(b.rows(), b.cols());
    const auto* values = static_cast<const double*>(x->x);
    for (Eigen::Index c = 0; c < b.cols(); ++c)
      for (Eigen::Index r = 0; r < b.rows(); ++r) out(r, c) = values[std::size_t(r) + std::size_t(c) * x->d];
    return out;
  }
};

const char* SparseCholesky::backendName() { return "CHOLMOD"; }

#else

struct SparseCholesky::Backend {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt;

  void factorize(const Eigen::SparseMatrix<double>& a) {
    ldlt.compute(a);
    if (ldlt.info() != Eigen::Success || (ldlt.vectorD().array() <= 0.0).any())
      throw RuntimeFailure("sparse Cholesky: matrix is not positive definite");
  }
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) { return ldlt.solve(b); }
};

const char* SparseCholesky::backendName() { return "Eigen SimplicialLDLT"; }

#endif

SparseCholesky::SparseCholesky() = default;
SparseCholesky::~SparseCholesky() = default;
SparseCholesky::SparseCholesky(SparseCholesky&&) noexcept = default;
SparseCholesky& SparseCholesky::operator=(SparseCholesky&&) noexcept = default;

void SparseCholesky::factorize(const Eigen::SparseMatrix<double>& A) {
  if (A.rows() != A.cols()) throw RuntimeFailure("sparse Cholesky: matrix is not square");
  factorized_ = false;
  n_ = A.rows();
  if (n_ == 0) {
    factorized_ = true;
    return;
  }
  Eigen::SparseMatrix<double> compressed = A;
  compressed.makeCompressed();
  backend_ = std::make_unique<Backend>();
  backend_->factorize(compressed);
  factorized_ = true;
}

Eigen::MatrixXd SparseCholesky::solve(const Eigen::MatrixXd& B) const {
  if (!factorized_) throw RuntimeFailure("sparse Cholesky: solve before factorize");
  if (B.rows() != n_) throw RuntimeFailure("sparse Cholesky: right-hand side has the wrong number of rows");
  if (n_ == 0 || B.cols() == 0) return Eigen::MatrixXd(B.rows(), B.cols());
  return backend_->solve(B);
}

}  // namespace vox
