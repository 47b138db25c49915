#pragma once
// Algebraic multigrid (smoothed aggregation) for symmetric sparse systems such as the cotangent
// stiffness K of vpm/laplacian.hpp: the hierarchy built on the host, one V-cycle as a
// preconditioner for CG (SolverOptions::preconditioner = amg; the OpenCL V-cycle lives in
// host/linalg/amg_device.*). Design after AMGCL's smoothed aggregation (docs/solver.md):
//
//   strength  |a_ij| >= eps_l sqrt(|a_ii a_jj|), eps_0 = strength, halved per level
//   aggregates greedy, three passes (roots whose strong neighbours are all free take them;
//             the rest attach to a neighbouring aggregate; leftovers group with their free
//             strong neighbours); rows without strong neighbours (and fixed rows) stay out
//   P         (I - omega D^-1 A_f) P_tent, P_tent 0/1 (so P 1 = 1 wherever A 1 = 0),
//             A_f = A with weak entries lumped into the diagonal, omega = 4/3 / rho(D^-1 A_f)
//             (Gershgorin bound); R = P^T; A_c = R A P (exact sparse triple product)
//   smoother  diagonal x += d (f - A x), d = SPAI-0 (a_ii / sum_j a_ij^2) or damped Jacobi;
//             one sweep before, one after: the V-cycle is symmetric, so CG stays valid
//   coarsest  an explicit dense (pseudo-)inverse: LDLT of A_c, with a rank-one shift along
//             the constants when A_c's rows sum to zero (the singular Neumann case)
//
// The sign of A does not matter (K is negative semi-definite: every step uses |.| or D^-1 A).
// Pattern and values are separated: the strength classification, the aggregates and the
// sparsity of every P and A_c are fixed at construction; update_values() recomputes only the
// numbers for new values on the same pattern (PoissonSolver::set_positions).
#include <Eigen/Core>
#include <vector>

#include "vpm/sparse.hpp"

namespace vpm {

enum class AmgSmoother {
  spai0,   ///< d_i = a_ii / sum_j a_ij^2 (no parameter)
  jacobi,  ///< d_i = jacobi_weight / a_ii
};

struct AmgOptions {
  double strength = 0.08;      ///< eps of the strength test on the finest level (halved per level)
  int coarse_size = 300;       ///< stop coarsening below this many rows (dense inverse there)
  int max_levels = 12;         ///< at most this many levels, the coarsest included
  AmgSmoother smoother = AmgSmoother::spai0;
  double jacobi_weight = 0.7;  ///< for AmgSmoother::jacobi
  int sweeps = 1;              ///< smoothing sweeps before and after the coarse correction
  bool operator==(const AmgOptions&) const = default;
};

/// One level of the hierarchy: its matrix, smoother diagonal and the transfers to the next.
struct AmgLevel {
  CsrMatrix A;             ///< this level's matrix (level 0: the input, fixed rows included)
  std::vector<double> d;   ///< smoother diagonal (0 on fixed / empty rows)
  CsrMatrix P, R;          ///< prolongation (rows x coarse rows) and R = P^T (empty on the coarsest)
};

/// The smoothed-aggregation hierarchy of a symmetric CSR matrix.
class AmgHierarchy {
 public:
  /// `a`: symmetric n x n (any definiteness sign; semi-definite with constant null space
  /// allowed). `fixed`: empty or length n, non-zero = a Dirichlet-eliminated row (its row and
  /// column are ignored, z = 0 there). Throws InputError on a non-square matrix.
  AmgHierarchy(const CsrMatrix& a, const std::vector<char>& fixed = {}, AmgOptions options = {});
  ~AmgHierarchy();
  AmgHierarchy(AmgHierarchy&&) noexcept;
  AmgHierarchy& operator=(AmgHierarchy&&) noexcept;

  /// New values of the same pattern (a.row_ptr, a.col equal to the construction's; else
  /// InputError): recomputes smoothers, P, A_c and the coarse inverse, keeping aggregates and
  /// sparsity.
  void update_values(const CsrMatrix& a);

  /// z = M^-1 r: one V-cycle from a zero start (host reference). Length n each. Uses work
  /// vectors held by the hierarchy: not for concurrent calls.
  void apply(const double* r, double* z) const;

  int num_levels() const { return static_cast<int>(levels_.size()); }
  const AmgLevel& level(int l) const { return levels_[l]; }
  /// The coarsest level's dense (pseudo-)inverse, row-major, size x size.
  const Eigen::MatrixXd& coarse_inverse() const { return coarse_inv_; }
  const std::vector<char>& fixed() const { return fixed_; }
  /// Sum of nnz over levels / nnz of level 0 (the cost of a V-cycle in spmvs of A, roughly).
  double operator_complexity() const;
  const AmgOptions& options() const { return options_; }

 private:
  struct Setup;  // per non-coarsest level: strong entries, aggregates, the pattern of A P
  void level_values(int l, std::vector<int>& pos);  // smoother, P, R, A_{l+1} of level l
  void finish_values();                             // coarse inverse, work vectors
  void compute_values();
  AmgOptions options_;
  std::vector<char> fixed_;
  std::vector<AmgLevel> levels_;
  std::vector<Setup> setup_;
  Eigen::MatrixXd coarse_inv_;
  mutable std::vector<std::vector<double>> work_;  // per level: f, out, x, r, t (5 n_l)
};

}  // namespace vpm
