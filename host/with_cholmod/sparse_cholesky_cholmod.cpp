// CHOLMOD's supernodal LLT (SuiteSparse, LGPL-2.1+/GPL-2+ Supernodal module) behind
// linalg/sparse_cholesky.hpp, through Eigen's CholmodSupport wrapper.
//
// The supernodes are factored by the BLAS, which OpenBLAS threads over every core by default.
// On the 16-core H200 machine (gVisor) that made one factorisation of the 10M-tet Colin27's
// boundary Laplacian 10x slower than one thread (4.3 s against 0.41 s; 4 threads 0.34 s), and
// the whole map 53 s against 32-36 s. So each call runs the BLAS on at most
// BlasThreadsScope::current() threads (linalg/sparse_cholesky.hpp: one unless the caller opened
// a scope; restored after), unless the user chose a count with OPENBLAS_NUM_THREADS. On the 2-core
// VM two threads factor the 128k-face Colin27 boundary's Laplacian (64k vertices) in 0.18 s
// against 0.26 s for one, and its whole surface map takes 0.87x the time (farm-bench, 4 pairs).
#include <dlfcn.h>

#include <Eigen/CholmodSupport>
#include <cstdlib>

#include "linalg/sparse_cholesky.hpp"

namespace vpm::detail {

namespace {

// OpenBLAS's thread count capped at BlasThreadsScope::current() for this object's lifetime, found at run time
// (no link to OpenBLAS: with another BLAS, or OPENBLAS_NUM_THREADS set, it does nothing).
class BoundedBlasThreads {
 public:
  BoundedBlasThreads() {
    if (std::getenv("OPENBLAS_NUM_THREADS")) return;
    static const auto get = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
    static const auto set = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    if (!get || !set) return;
    saved_ = get();
    const int cap = BlasThreadsScope::current();
    if (saved_ <= cap) return;
    set_ = set;
    set_(cap);
  }
  ~BoundedBlasThreads() {
    if (set_) set_(saved_);
  }
  BoundedBlasThreads(const BoundedBlasThreads&) = delete;
  BoundedBlasThreads& operator=(const BoundedBlasThreads&) = delete;

 private:
  void (*set_)(int) = nullptr;
  int saved_ = 1;
};

class CholmodSupernodal final : public CholeskyBackend {
 public:
  CholmodSupernodal() { llt_.cholmod().print = 0; }  // not positive definite is not news: the caller falls back
  bool factorize(const Eigen::SparseMatrix<double>& a, bool same_pattern) override {
    const BoundedBlasThreads bounded;
    if (!(same_pattern && analysed_)) {
      llt_.analyzePattern(a);
      analysed_ = llt_.info() == Eigen::Success;
      if (!analysed_) return false;
    }
    llt_.factorize(a);
    return llt_.info() == Eigen::Success;
  }
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const override {
    const BoundedBlasThreads bounded;
    return llt_.solve(b);
  }
  const char* name() const override { return "cholmod-supernodal"; }

 private:
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt_;
  bool analysed_ = false;
};

}  // namespace

std::unique_ptr<CholeskyBackend> make_cholmod_backend() { return std::make_unique<CholmodSupernodal>(); }

}  // namespace vpm::detail
