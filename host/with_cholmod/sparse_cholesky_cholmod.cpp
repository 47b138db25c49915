// CHOLMOD's supernodal LLT (SuiteSparse, LGPL-2.1+/GPL-2+ Supernodal module) behind
// linalg/sparse_cholesky.hpp, through Eigen's CholmodSupport wrapper.
#include <Eigen/CholmodSupport>

#include "linalg/sparse_cholesky.hpp"

namespace vpm::detail {

namespace {

class CholmodSupernodal final : public CholeskyBackend {
 public:
  CholmodSupernodal() { llt_.cholmod().print = 0; }  // a matrix not positive definite is not news: the caller falls back
  bool factorize(const Eigen::SparseMatrix<double>& a, bool same_pattern) override {
    if (!(same_pattern && analysed_)) {
      llt_.analyzePattern(a);
      analysed_ = llt_.info() == Eigen::Success;
      if (!analysed_) return false;
    }
    llt_.factorize(a);
    return llt_.info() == Eigen::Success;
  }
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const override { return llt_.solve(b); }
  const char* name() const override { return "cholmod-supernodal"; }

 private:
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt_;
  bool analysed_ = false;
};

}  // namespace

std::unique_ptr<CholeskyBackend> make_cholmod_backend() { return std::make_unique<CholmodSupernodal>(); }

}  // namespace vpm::detail
