#pragma once
// Private: the Laplacian systems of the sphere map's area equalisation (map/sphere_density.cpp),
// one per step, each with the pinned cotangent Laplacian of the current sphere mesh (the same
// pattern every step, new values).
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>

namespace vpm {
class Device;
}

namespace vpm::detail {

/// Solves L u = b for symmetric positive definite L: by Jacobi CG on `device` when one is given
/// (relative residual 1e-10, warm-started from the previous step's solution), else on the host
/// by sparse Cholesky with an earlier step's factor reused as CG preconditioner. A device solve
/// that fails (no convergence) is redone on the host.
class DensitySolver {
 public:
  explicit DensitySolver(Device* device);
  ~DensitySolver();
  DensitySolver(const DensitySolver&) = delete;
  DensitySolver& operator=(const DensitySolver&) = delete;
  /// False when neither path gave a finite solution.
  bool solve(const Eigen::SparseMatrix<double>& L, const Eigen::VectorXd& b, Eigen::VectorXd& x);
  /// "device-amg-cg", "cholmod-supernodal" or "eigen-simplicial-ldlt": what solved the last system.
  const char* name() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vpm::detail
