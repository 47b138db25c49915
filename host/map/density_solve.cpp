// The sphere map's area-equalisation solves (map/density_solve.hpp).
#include "map/density_solve.hpp"

#include <Eigen/Sparse>
#include <algorithm>

#include "linalg/sparse_cholesky.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/solver.hpp"
#include "vpm/sparse.hpp"

namespace vpm::detail {

namespace {

using SpMat = Eigen::SparseMatrix<double>;

// Solves the density steps' systems L u = b. The Laplacians of successive steps differ by the
// step's change of shape, so the factor of an earlier step's L preconditions CG on the current
// one (a pair of triangular solves an iteration): a new factor is made when CG needed more
// than kRefactorAfter iterations last time or does not converge within kMaxIterations. On the
// 10M-tet Colin27's boundary (136k vertices, 13 steps) that is 4 factorisations instead of 13,
// and the whole sphere map 6.45 -> 5.55 s on the 2-core VM with CHOLMOD (one CG iteration
// 20 ms, one factorisation 0.33 s), 14.7 -> 8.3 s with Eigen's SimplicialLDLT (factorisation
// 1.0 s). The flow needs its velocity, not 12 digits of it: at a relative residual of 1e-8
// (refactoring after 8) the 13 steps take 70 iterations instead of 104, the solves 3.8 -> 3.3 s
// there, and the sphere moves by 2e-10; but that was enough to turn the fragile hand of
// bench/shapes (30k) from 0.97 % (exit 0) into 2.52 % (exit 4), so the tolerance stays 1e-12.
class FactorReuse {
 public:
  bool solve(const SpMat& L, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
    if (factored_ && last_iterations_ <= kRefactorAfter && pcg(L, b, x)) return true;
    if (!chol_.factorize(L, factored_)) return false;
    factored_ = true;
    last_iterations_ = 0;
    x = chol_.solve(b);
    return x.allFinite();
  }
  const char* backend() const { return chol_.backend(); }

 private:
  static constexpr int kRefactorAfter = 12, kMaxIterations = 40;
  static constexpr double kTolerance = 1e-12;

  bool pcg(const SpMat& L, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
    const double bn = b.norm();
    x = chol_.solve(b);
    Eigen::VectorXd r = b - L * x;
    Eigen::VectorXd z = chol_.solve(r), p = z;
    double rz = r.dot(z);
    for (int it = 1; it <= kMaxIterations; ++it) {
      if (!(r.norm() > kTolerance * bn)) {
        last_iterations_ = it - 1;
        return x.allFinite();
      }
      const Eigen::VectorXd q = L * p;
      const double alpha = rz / p.dot(q);
      x += alpha * p;
      r -= alpha * q;
      z = chol_.solve(r);
      const double rz_next = r.dot(z);
      p = z + (rz_next / rz) * p;
      rz = rz_next;
    }
    last_iterations_ = kMaxIterations + 1;
    return false;
  }

  SparseCholesky chol_;
  bool factored_ = false;
  int last_iterations_ = 0;
};

// AMG-preconditioned CG on the device (vpm/amg.hpp: the hierarchy built on the host for each
// step's matrix, the V-cycles on the device), warm-started from the previous step's solution.
// On the 10M-tet Colin27's boundary (136,449 vertices) 29-33 iterations a step, where Jacobi CG
// took 1,700-1,950: the 13 steps' solves 2.5 s on the 2-core PoCL device against 3.8 s for the
// host's Cholesky and 14.7 s for Jacobi CG; on the 1.1M one's (32,098) 0.64-0.68 s against
// 0.62-0.66 s. InitialMapOptions::DensitySolve::automatic uses it on GPUs only (on CPUs its
// kernels compete with the host threads of the rest of the map: vpm/initial_map.hpp).
class DeviceCg {
 public:
  explicit DeviceCg(Device& device) : device_(device) {}
  bool solve(const SpMat& L, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
    SolverOptions o;
    o.relative_tolerance = 1e-10;
    o.max_iterations = std::max(20000, 4 * static_cast<int>(L.rows()));
    o.preconditioner = Preconditioner::amg;
    try {
      SparseSolver cg(device_, CsrMatrix::from_eigen(L), o);
      x = last_.size() == b.size() ? last_ : Eigen::VectorXd::Zero(b.size());
      cg.solve(b, x);
    } catch (const NumericalError&) {
      return false;
    }
    if (!x.allFinite()) return false;
    last_ = x;
    return true;
  }

 private:
  Device& device_;
  Eigen::VectorXd last_;
};

}  // namespace

struct DensitySolver::Impl {
  std::unique_ptr<DeviceCg> device;
  FactorReuse host;
  const char* last = "";
};

DensitySolver::DensitySolver(Device* device) : impl_(std::make_unique<Impl>()) {
  if (device && !device->is_host()) impl_->device = std::make_unique<DeviceCg>(*device);
}

DensitySolver::~DensitySolver() = default;

bool DensitySolver::solve(const SpMat& L, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  if (impl_->device && impl_->device->solve(L, b, x)) {
    impl_->last = "device-amg-cg";
    return true;
  }
  if (!impl_->host.solve(L, b, x)) return false;
  impl_->last = impl_->host.backend();
  return true;
}

const char* DensitySolver::name() const { return impl_->last; }

}  // namespace vpm::detail
