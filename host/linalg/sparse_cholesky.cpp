#include "linalg/sparse_cholesky.hpp"

#include "vpm/config.hpp"

namespace vpm::detail {

#if !VPM_HAVE_CHOLMOD
std::unique_ptr<CholeskyBackend> make_cholmod_backend() { return nullptr; }
#endif

namespace {
thread_local int t_max_blas_threads = 1;
}  // namespace

BlasThreadsScope::BlasThreadsScope(int max_threads) : saved_(t_max_blas_threads) {
  t_max_blas_threads = max_threads < 1 ? 1 : max_threads;
}
BlasThreadsScope::~BlasThreadsScope() { t_max_blas_threads = saved_; }
int BlasThreadsScope::current() { return t_max_blas_threads; }

SparseCholesky::SparseCholesky() : cholmod_(make_cholmod_backend()) {}
SparseCholesky::~SparseCholesky() = default;

bool SparseCholesky::factorize(const Eigen::SparseMatrix<double>& a, bool same_pattern) {
  if (cholmod_ && cholmod_->factorize(a, same_pattern)) {
    use_cholmod_ = true;
    return true;
  }
  use_cholmod_ = false;
  if (!ldlt_) ldlt_ = std::make_unique<Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>>();
  if (!(same_pattern && ldlt_analysed_)) {
    ldlt_->analyzePattern(a);
    ldlt_analysed_ = true;
  }
  ldlt_->factorize(a);
  return ldlt_->info() == Eigen::Success;
}

Eigen::MatrixXd SparseCholesky::solve(const Eigen::MatrixXd& b) const {
  if (use_cholmod_) return cholmod_->solve(b);
  return ldlt_->solve(b);
}

Eigen::VectorXd SparseCholesky::solve(const Eigen::VectorXd& b) const {
  if (use_cholmod_) return cholmod_->solve(b);
  return ldlt_->solve(b);
}

const char* SparseCholesky::backend() const {
  return use_cholmod_ ? cholmod_->name() : "eigen-simplicial-ldlt";
}

}  // namespace vpm::detail
