#pragma once
// A sparse Cholesky factorisation for the host's direct solves (the sphere map's Laplacians,
// map/sphere_steps.cpp and map/sphere_density.cpp).
//
// With CHOLMOD (SuiteSparse, host/with_cholmod/) the factor is supernodal: dense supernodes
// factored with BLAS-3, multithreaded through the BLAS (OpenBLAS). On the 10M-tet Colin27's
// boundary (136k vertices) one factorisation takes 0.24-0.30 s on 2 cores against 1.0 s for
// Eigen's SimplicialLDLT; at 32k vertices both take about 0.06 s. Without CHOLMOD, or when
// CHOLMOD finds the matrix not positive definite, Eigen's SimplicialLDLT factors it.
#include <Eigen/Sparse>
#include <memory>

namespace vpm::detail {

/// A factorisation backend (host/with_cholmod/): factors a symmetric positive definite matrix,
/// both triangles stored; with `same_pattern` the ordering and symbolic analysis of the previous
/// call are reused (the caller promises the same sparsity pattern).
class CholeskyBackend {
 public:
  virtual ~CholeskyBackend() = default;
  virtual bool factorize(const Eigen::SparseMatrix<double>& a, bool same_pattern) = 0;
  virtual Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const = 0;
  virtual const char* name() const = 0;
};
/// The most BLAS threads CHOLMOD's factorisations and solves on the calling thread use while the
/// scope lives (fewer when the BLAS has fewer; OPENBLAS_NUM_THREADS, when set, decides instead).
/// Outside any scope: one. The tet map's sphere map runs beside the edge split and the harmonic
/// solver's set-up: there 2 threads on the 2-core VM gained no time (0.98-1.02x) and their
/// round-off turned bench/shapes' hand from 0.92 % (exit 0) into 2.45 % (exit 4). The surface map
/// runs its sphere map alone and opens a scope of 4 (4 were the fastest on a 16-core machine).
class BlasThreadsScope {
 public:
  explicit BlasThreadsScope(int max_threads);
  ~BlasThreadsScope();
  BlasThreadsScope(const BlasThreadsScope&) = delete;
  BlasThreadsScope& operator=(const BlasThreadsScope&) = delete;
  /// The calling thread's current bound.
  static int current();

 private:
  int saved_;
};

/// CHOLMOD's supernodal LLT, or nullptr when vpm was built without CHOLMOD.
std::unique_ptr<CholeskyBackend> make_cholmod_backend();

/// Sparse Cholesky of a symmetric positive (semi-)definite matrix: CHOLMOD supernodal when
/// available and the matrix is positive definite, else Eigen's SimplicialLDLT.
class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// Factors `a` (both triangles stored). With `same_pattern` (a promise that `a` has the
  /// sparsity pattern of the previous call) the fill-reducing ordering is reused. False if
  /// neither backend could factor it.
  bool factorize(const Eigen::SparseMatrix<double>& a, bool same_pattern = false);
  /// x = A^-1 b for the last factored A (one column or several).
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  /// "cholmod-supernodal" or "eigen-simplicial-ldlt": which backend holds the current factor.
  const char* backend() const;

 private:
  std::unique_ptr<CholeskyBackend> cholmod_;
  std::unique_ptr<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>> ldlt_;
  bool use_cholmod_ = false, ldlt_analysed_ = false;
};

}  // namespace vpm::detail
