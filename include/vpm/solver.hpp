#pragma once
// Sparse iterative solvers on the host or an OpenCL device: Jacobi-preconditioned CG for
// symmetric (also singular Neumann) systems, Dirichlet rows eliminated, and BiCGSTAB for
// non-symmetric systems and for the paper's normal-equations option (`--solver paper`).
//
// The algorithms are written once over a small backend (spmv, dots, fused vector updates) with
// a host backend (plain loops) and an OpenCL backend (kernels/solver.cl); on the device all
// scalars stay on the device and the host reads one residual per iteration.
//
// Every solve either reaches ||b - A x||_2 <= relative_tolerance * ||b||_2 or throws
// vpm::NumericalError with the residual reached: there is never a silent unconverged result.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "vpm/amg.hpp"
#include "vpm/laplacian.hpp"
#include "vpm/mesh.hpp"
#include "vpm/sparse.hpp"

namespace vpm {

class Device;

enum class SolverMethod {
  cg,        ///< Jacobi-preconditioned conjugate gradients (symmetric A; singular allowed)
  bicgstab,  ///< Jacobi-preconditioned BiCGSTAB on A x = b (any square A)
  paper,     ///< BiCGSTAB on the normal equations A^T A x = A^T b (the paper's choice: it
             ///< squares the condition number; for comparison only)
};
/// "cg", "bicgstab", "paper" (InputError otherwise).
SolverMethod parse_solver_method(const std::string& name);
const char* to_string(SolverMethod m);

/// Preconditioner of `cg` (bicgstab and paper always use Jacobi).
enum class Preconditioner {
  jacobi,  ///< diagonal, fused into the CG updates (the default)
  amg,     ///< one smoothed-aggregation V-cycle (vpm/amg.hpp) per iteration, on the solver's
           ///< device; the hierarchy is built on the host once per matrix pattern and mask
};
/// "jacobi", "amg" (InputError otherwise).
Preconditioner parse_preconditioner(const std::string& name);

/// What a caller asks for: one preconditioner, or the choice by device and mesh size.
enum class PreconditionerChoice { automatic, jacobi, amg };
/// "auto", "jacobi", "amg" (InputError otherwise), and back.
PreconditionerChoice parse_preconditioner_choice(const std::string& name);
const char* to_string(PreconditionerChoice choice);

/// Meshes from this many tets on get AMG from PreconditionerChoice::automatic on CPU devices:
/// whole `vpm map` of Colin27 on 2 cores, AMG against Jacobi, 1.00x at 383k tets, 1.04x at 688k,
/// 1.10x at 2.2M, for 14-17 % more memory (bench/results/solver_amg_600k/).
inline constexpr long long kAutoAmgTets = 600'000;
/// The preconditioner `choice` stands for on `device` for the Laplacian of a mesh of `tets`
/// tets: jacobi and amg as named; automatic: AMG on CPU devices (the host and OpenCL CPU
/// devices) from kAutoAmgTets tets on, Jacobi below and on GPUs: on CPUs AMG's fewer iterations
/// win on large meshes for some more memory, on a GPU Jacobi-CG iterations cost microseconds
/// while AMG's value update runs on the host (measurements: bench/results/solver_amg_auto/,
/// bench/results/gpu_h200_19s/).
Preconditioner choose_preconditioner(PreconditionerChoice choice, const Device& device, long long tets);
const char* to_string(Preconditioner p);

struct SolverOptions {
  /// Stop when the true residual ||b - A x||_2 <= relative_tolerance * ||b||_2 (b: the right
  /// side after Dirichlet elimination). For `paper` the test is on the normal equations,
  /// ||A^T (b - A x)|| <= tol ||A^T b||, and SolverStats reports the original system's residual.
  double relative_tolerance = 1e-8;
  /// Iteration cap per right-hand side; reaching it throws NumericalError.
  int max_iterations = 20000;
  SolverMethod method = SolverMethod::cg;
  /// Neumann compatibility: |sum b| <= neumann_tolerance * sum |b| or InputError. The small
  /// remaining mean is then removed from b before solving.
  double neumann_tolerance = 1e-10;
  /// Preconditioner of `cg`; `amg` options below.
  Preconditioner preconditioner = Preconditioner::jacobi;
  AmgOptions amg;
};

struct SolverStats {
  int iterations = 0;              ///< iterations of the last solve (summed over columns for k > 1)
  double relative_residual = 0;    ///< ||b - A x|| / ||b|| reached (worst column for k > 1)
  double seconds = 0;              ///< wall time of the solve call, including transfers
  /// Part of `seconds` spent building or updating the AMG hierarchy (and uploading it); 0
  /// for Jacobi or when the hierarchy was current.
  double setup_seconds = 0;
};

/// Solves with a fixed general CSR matrix on a device (square, any symmetry for bicgstab/paper,
/// symmetric for cg). Keeps the matrix and work vectors on the device between solves.
class SparseSolver {
 public:
  /// `a`: n x n CSR. The device must outlive the solver.
  SparseSolver(Device& device, const CsrMatrix& a, SolverOptions options = {});
  ~SparseSolver();
  /// Solves A x = b. `b` length n; `x` length n, in: initial guess (warm start; resized and
  /// zero-filled if its length is not n), out: the solution. Throws NumericalError on
  /// non-convergence (message gives the residual reached and the iteration count).
  SolverStats solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  SolverOptions& options() { return options_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  SolverOptions options_;
};

/// Poisson-type problems on a tet mesh with the cotangent stiffness K of vpm/laplacian.hpp
/// (negative semi-definite; rows sum to zero). Stateful: the pattern, the slot map and every
/// device buffer are built once per connectivity; set_positions() refreshes K on the device.
class PoissonSolver {
 public:
  /// `num_vertices` = n, `tets` m x 4 (0-based, positively oriented). The device must outlive
  /// the solver. Call set_positions() before the first solve.
  PoissonSolver(Device& device, int num_vertices, const Tets& tets, SolverOptions options = {});
  ~PoissonSolver();

  /// Re-assembles K (and the lumped mass) for `vertices` (n x 3) on the solver's device.
  void set_positions(const Points& vertices);

  /// Neumann problem K x = b (singular: the constant is projected out).
  /// `b`: length n, units of K x (length x units of x); must sum to zero within
  /// options().neumann_tolerance * sum|b| or InputError is thrown (e.g. Moser's V - m, with m
  /// rescaled to the current total volume). `x`: length n, in: warm start (e.g. the previous
  /// step's solution; resized and zero-filled if the length is wrong), out: the solution with
  /// zero (unweighted) mean.
  SolverStats solve_neumann(const Eigen::VectorXd& b, Eigen::VectorXd& x);

  /// Dirichlet problem: K x = rhs on free vertices, x = values on fixed ones (rows and columns
  /// of fixed vertices eliminated, so CG sees a symmetric definite system).
  /// `fixed`: length n, non-zero = fixed vertex (e.g. boundary_vertex_mask()).
  /// `values`: n x k, only the fixed rows are read (e.g. sphere positions, k = 3).
  /// `x`: n x k, in: warm start for the free rows (resized and zero-filled if its shape is
  /// wrong), out: the solution (fixed rows = values). `rhs`: n x k or nullptr for zero (the
  /// harmonic map). With Jacobi CG the columns are solved in blocks of up to three (one pass
  /// over the matrix per iteration for all), otherwise one after another; either way each
  /// column's result is that of solving it alone, bit for bit. The stats give the summed
  /// iterations and the worst residual. Throws InputError if no vertex is fixed.
  SolverStats solve_dirichlet(const std::vector<char>& fixed, const FieldValues& values,
                              FieldValues& x, const FieldValues* rhs = nullptr);

  const CotanLaplacian& laplacian() const { return laplacian_; }
  SolverOptions& options() { return options_; }
  Device& device() const { return device_; }
  /// Frees what later solves would rebuild on demand: the block solves' extra vectors and the
  /// multigrid hierarchies (for a solver handed on to another stage, e.g. the initial map's to
  /// the volume map).
  void release_work_memory();
  const SolverStats& last_stats() const { return last_; }

 private:
  struct Impl;
  Device& device_;
  CotanLaplacian laplacian_;
  SolverOptions options_;
  SolverStats last_;
  std::unique_ptr<Impl> impl_;
};

/// One-call helpers on Device::current() (or `device` when given).
/// Neumann: returns the zero-mean x with K(vertices) x = b (see PoissonSolver::solve_neumann).
Eigen::VectorXd solve_neumann(const Points& vertices, const Tets& tets, const Eigen::VectorXd& b,
                              const SolverOptions& options = {}, Device* device = nullptr,
                              SolverStats* stats = nullptr);
/// Dirichlet: returns x (n x k) with x = values on fixed rows and K x = 0 elsewhere (a harmonic
/// map when values are boundary positions). Shapes as in PoissonSolver::solve_dirichlet.
FieldValues solve_dirichlet(const Points& vertices, const Tets& tets,
                            const std::vector<char>& fixed, const FieldValues& values,
                            const SolverOptions& options = {}, Device* device = nullptr,
                            SolverStats* stats = nullptr);
/// General: solves A x = b (x zero-started) with `options.method`.
Eigen::VectorXd solve(const CsrMatrix& a, const Eigen::VectorXd& b, const SolverOptions& options = {},
                      Device* device = nullptr, SolverStats* stats = nullptr);

}  // namespace vpm
