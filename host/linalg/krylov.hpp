#pragma once
// Private: the Krylov solvers written once over a backend of primitives (linalg/solver_backend.hpp:
// HostBackend, the Eigen/C++ reference, and ClBackend, the OpenCL kernels of kernels/solver.cl).
// Used by SparseSolver and PoissonSolver (vpm/solver.hpp).
#include <cmath>
#include <string>
#include <vector>

#include "linalg/solver_backend.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/solver.hpp"
#include "vpm/timing.hpp"

namespace vpm::detail {


[[noreturn]] inline void not_converged(SolverMethod m, double rel, int its, double tol, int n,
                                const char* why) {
  throw NumericalError(std::string("solver ") + to_string(m) + " " + why + ": relative residual " +
                       format_sig(rel, 3) + " after " + std::to_string(its) + " iterations (tolerance " +
                       format_sig(tol, 3) + ", " + std::to_string(n) + " unknowns)");
}

// y = (A D) x, or (A^T A D) x for the normal equations (uses VTMP).
template <class BK>
void apply_scaled(BK& bk, Vec y, Vec x, bool normal) {
  if (normal) {
    bk.spmv_scaled(VTMP, x);
    bk.spmv(y, VTMP, true);
  } else {
    bk.spmv_scaled(y, x);
  }
}

// The host's side of one Krylov run: the device runs up to `lookahead` iterations ahead of the
// residual the host reads (one read per iteration), and the run ends at the first residual
// within tol2, the iteration already queued after it included. krylov() keeps one; a block
// solve (linalg/krylov_block.hpp) keeps one per column, so each column takes exactly the
// iterations of a lone run. Throws NumericalError on breakdown or at `max_iterations`.
struct KrylovPace {
  SolverMethod method;
  double tol2, bnorm2, tol;
  int n, max_iterations, lookahead;
  int enqueued = 0, done = 0;
  bool stop = false, finished = false;

  /// The start's residual; true when it meets tol2 already (no iteration to run).
  bool start(double rr) {
    if (!std::isfinite(rr)) not_converged(method, rr, 0, tol, n, "started from a non-finite residual");
    finished = rr <= tol2;
    if (!finished && max_iterations <= 0)
      not_converged(method, std::sqrt(rr / bnorm2), 0, tol, n, "did not converge");
    return finished;
  }
  /// Whether another iteration may be queued now.
  bool may_enqueue() const {
    return !finished && !stop && enqueued < max_iterations && enqueued < done + lookahead;
  }
  /// An iteration is queued: the residual slot (0/1) its read goes to.
  int enqueue() { return enqueued++ % 2; }
  /// The slot of the next residual to read.
  int next_read() const { return done % 2; }
  /// Takes that residual; true when the run is over (after `done` iterations).
  bool read(double rr) {
    ++done;
    if (!std::isfinite(rr)) not_converged(method, rr, done, tol, n, "broke down (non-finite residual)");
    if (rr <= tol2) {
      if (done == enqueued) return finished = true;
      stop = true;  // the iteration already queued gives the result
    } else if (done == enqueued) {
      stop = false;
      if (done >= max_iterations)
        not_converged(method, std::sqrt(rr / bnorm2), done, tol, n, "did not converge");
    }
    return false;
  }
};

// The Krylov loop, written once for both backends. Precondition: VX holds the start, VR its
// residual (of the normal equations for `paper`). Runs until the recursive residual satisfies
// rr <= tol2 (one read of it per iteration; the device runs `lookahead` iterations ahead of
// the host so it never idles while the host checks). Returns the iterations done; *rr_out the
// last recursive squared residual. Throws NumericalError on breakdown or at `max_iterations`.
template <class BK>
int krylov(BK& bk, SolverMethod method, double tol2, int max_iterations, double* rr_out,
           double bnorm2, double tol) {
  const bool cg = method == SolverMethod::cg;
  const bool normal = method == SolverMethod::paper;
  const bool pcg = cg && bk.has_amg();  // general preconditioner path (z = M^-1 r)
  if (pcg) {
    bk.precondition();
    bk.dot2(VR, VZ, VR, VR, OP_CG_INIT);
    bk.copy(VP, VZ);
  } else if (cg) {
    bk.cg_init();
  } else {
    bk.copy(VR0, VR);
    bk.copy(VP, VR);
    bk.dot2(VR0, VR, VR, VR, OP_BI_INIT);
  }
  KrylovPace pace{method, tol2, bnorm2, tol, bk.size(), max_iterations, bk.lookahead()};
  double rr = bk.read_rr_now();
  *rr_out = rr;
  if (pace.start(rr)) return 0;
  auto step = [&] {
    if (pcg) {
      bk.spmv(VQ, VP, false);
      bk.dot(VP, VQ, OP_CG_ALPHA);
      bk.pcg_update_xr();
      bk.precondition();
      bk.dot2(VR, VZ, VR, VR, OP_CG_BETA);
      bk.pcg_update_p();
    } else if (cg) {
      bk.spmv(VQ, VP, false);
      bk.dot(VP, VQ, OP_CG_ALPHA);
      bk.cg_update_xr();
      bk.cg_update_p();
    } else {
      apply_scaled(bk, VQ, VP, normal);  // v
      bk.dot(VR0, VQ, OP_BI_ALPHA);
      bk.bicg_s();
      apply_scaled(bk, VT, VS, normal);  // t
      bk.dot2(VT, VS, VT, VT, OP_BI_OMEGA);
      bk.bicg_update();
      bk.bicg_p();
    }
  };
  while (true) {
    while (pace.may_enqueue()) {
      step();
      bk.request_rr(pace.enqueue());
    }
    rr = bk.wait_rr(pace.next_read());
    *rr_out = rr;
    if (pace.read(rr)) return pace.done;
  }
}

// One right-hand side's solve, split in steps so that a block solve (linalg/krylov_block.hpp)
// can run the first Krylov run of several columns together: begin(), runs(), end().
struct SolveState {
  bool normal = false;
  double borig2 = 0, bnorm2 = 0, tol = 0, tol2 = 0, rr_true = 0;
  SolverStats stats;
};

// VR = the true residual (of the normal equations for `paper`); returns its squared norm.
template <class BK>
double true_residual(BK& bk, const SolveState& s) {
  if (s.normal) {
    bk.residual(VTMP, VB, VX);
    bk.spmv(VR, VTMP, true);
  } else {
    bk.residual(VR, VB, VX);
  }
  bk.dot(VR, VR, OP_NORM);
  return bk.read_rr_now();
}

// Uploads b and the start x, measures the right side and sets VR to the start's residual.
// False when the effective right side is 0: x then holds the solution (x_fixed, 0 elsewhere).
template <class BK>
bool solve_begin(BK& bk, const SolverOptions& opt, const std::vector<char>& mask, const double* b,
                 double* x, SolveState& s) {
  const int n = bk.size();
  s.normal = opt.method == SolverMethod::paper;
  bk.set_preconditioner(s.normal);
  bk.upload(VB, b);
  // b_eff = b - A x_fixed on free rows
  std::vector<double> xc(x, x + n);
  for (int i = 0; i < n; ++i)
    if (!mask[i]) xc[i] = 0;
  bk.upload(VX, xc.data());
  bk.residual(VTMP, VB, VX);
  bk.dot(VTMP, VTMP, OP_NORM);
  s.borig2 = bk.read_rr_now();
  s.bnorm2 = s.borig2;
  if (s.normal) {
    bk.spmv(VR, VTMP, true);
    bk.dot(VR, VR, OP_NORM);
    s.bnorm2 = bk.read_rr_now();
  }
  if (!std::isfinite(s.bnorm2))
    throw NumericalError("solver: the right-hand side (or the matrix) is not finite");
  if (s.bnorm2 == 0) {
    std::copy(xc.begin(), xc.end(), x);
    return false;
  }
  s.tol = opt.relative_tolerance;
  s.tol2 = s.tol * s.tol * s.bnorm2;
  bk.upload(VX, x);
  s.rr_true = true_residual(bk, s);
  return true;
}

// Krylov runs until the true residual meets the tolerance (the recursive one can drift from
// it), restarting from the true residual at most 4 runs in all; `done` runs were made already.
template <class BK>
void solve_runs(BK& bk, const SolverOptions& opt, SolveState& s, int done) {
  for (;; ++done) {
    if (done > 0) {
      s.rr_true = true_residual(bk, s);
      if (s.rr_true <= s.tol2) return;
      if (done == 4 || s.stats.iterations >= opt.max_iterations)
        not_converged(opt.method, std::sqrt(s.rr_true / s.bnorm2), s.stats.iterations, s.tol, bk.size(),
                      "did not converge (true residual above tolerance after restarts)");
    }
    double rr = 0;
    s.stats.iterations +=
        krylov(bk, opt.method, s.tol2, opt.max_iterations - s.stats.iterations, &rr, s.bnorm2, s.tol);
  }
}

// Downloads x and sets the relative residual.
template <class BK>
void solve_end(BK& bk, double* x, SolveState& s) {
  bk.download(VX, x);
  if (s.normal) {
    bk.residual(VTMP, VB, VX);
    bk.dot(VTMP, VTMP, OP_NORM);
    s.stats.relative_residual = std::sqrt(bk.read_rr_now() / s.borig2);
  } else {
    s.stats.relative_residual = std::sqrt(s.rr_true / s.bnorm2);
  }
}

// Solves A x = b on the backend (matrix, mask set). `b`, `x` length n; x in: start (fixed rows
// hold the Dirichlet values), out: solution. Fixed rows of x are not changed.
template <class BK>
SolverStats solve_system(BK& bk, const SolverOptions& opt, const std::vector<char>& mask,
                         const double* b, double* x) {
  SolveState s;
  if (!solve_begin(bk, opt, mask, b, x, s)) return s.stats;
  solve_runs(bk, opt, s, 0);
  solve_end(bk, x, s);
  return s.stats;
}

}  // namespace vpm::detail
