#pragma once
// Private: the linear solves of the volume-preserving map behind one small interface, on the
// shared solver module (vpm/solver.hpp: Jacobi CG or the paper's normal equations, host or
// OpenCL): PoissonSolver for the Neumann problems, SparseSolver for the reweighted (vsem)
// Dirichlet problems.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

#include "vpm/mesh.hpp"
#include "vpm/solver.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

struct SolveStats {
  int iterations = 0;
  double residual = 0;
  double seconds = 0;
};

/// Cotangent stiffness with the sign of vpm/laplacian.hpp (negative semi-definite):
/// K_ij = -sum_t w_t V_t grad phi_i . grad phi_j over tets t of positions `x` (w_t = 1 when
/// `weights` is null). n x n.
Eigen::SparseMatrix<double> weighted_stiffness(const Points& x, const Tets& tets,
                                               const Eigen::VectorXd* weights = nullptr);

class MapSolver {
 public:
  /// `method`: cg or paper (normal equations, BiCGSTAB; bicgstab is refused). `tolerance`:
  /// relative residual. `preconditioner` (of cg; vpm::choose_preconditioner resolves automatic
  /// for the device and the tet count). `reuse`: a PoissonSolver built on the same tets and
  /// device to use for the Neumann solves (ignored otherwise; nullptr: one is built).
  MapSolver(Device& device, int num_vertices, const Tets& tets, SolverMethod method, double tolerance,
            PreconditionerChoice preconditioner = PreconditionerChoice::jacobi,
            std::shared_ptr<PoissonSolver> reuse = nullptr);
  ~MapSolver();
  /// The preconditioner the Neumann solves use (what "auto" resolved to).
  Preconditioner preconditioner() const;
  /// Neumann: K(x) psi = b (b sums to zero); psi in: warm start, out: zero-mean solution.
  SolveStats neumann(const Points& x, const Eigen::VectorXd& b, Eigen::VectorXd& psi);
  /// Dirichlet with a given matrix K (negative semi-definite, e.g. weighted_stiffness):
  /// K X = 0 on rows with fixed == 0, X = given on fixed rows. X n x 3, in/out.
  SolveStats dirichlet(const Eigen::SparseMatrix<double>& K, const std::vector<char>& fixed, Points& X);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vpm::detail
