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
  double rr = bk.read_rr_now();
  if (!std::isfinite(rr))
    not_converged(method, rr, 0, tol, bk.size(), "started from a non-finite residual");
  *rr_out = rr;
  if (rr <= tol2) return 0;
  if (max_iterations <= 0) not_converged(method, std::sqrt(rr / bnorm2), 0, tol, bk.size(), "did not converge");
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
  int enqueued = 0, done = 0;
  bool stop = false;
  while (true) {
    while (!stop && enqueued < max_iterations && enqueued < done + bk.lookahead()) {
      step();
      bk.request_rr(enqueued % 2);
      ++enqueued;
    }
    rr = bk.wait_rr(done % 2);
    ++done;
    *rr_out = rr;
    if (!std::isfinite(rr))
      not_converged(method, rr, done, tol, bk.size(), "broke down (non-finite residual)");
    if (rr <= tol2) {
      if (done == enqueued) return done;
      stop = true;  // the iteration already queued gives the result
    } else if (done == enqueued) {
      stop = false;
      if (done >= max_iterations)
        not_converged(method, std::sqrt(rr / bnorm2), done, tol, bk.size(), "did not converge");
    }
  }
}

// Solves A x = b on the backend (matrix, mask set). `b`, `x` length n; x in: start (fixed rows
// hold the Dirichlet values), out: solution. Fixed rows of x are not changed.
template <class BK>
SolverStats solve_system(BK& bk, const SolverOptions& opt, const std::vector<char>& mask,
                         const double* b, double* x) {
  const int n = bk.size();
  const bool normal = opt.method == SolverMethod::paper;
  SolverStats st;
  bk.set_preconditioner(normal);
  bk.upload(VB, b);
  // b_eff = b - A x_fixed on free rows
  std::vector<double> xc(x, x + n);
  for (int i = 0; i < n; ++i)
    if (!mask[i]) xc[i] = 0;
  bk.upload(VX, xc.data());
  bk.residual(VTMP, VB, VX);
  bk.dot(VTMP, VTMP, OP_NORM);
  const double borig2 = bk.read_rr_now();
  double bnorm2 = borig2;
  if (normal) {
    bk.spmv(VR, VTMP, true);
    bk.dot(VR, VR, OP_NORM);
    bnorm2 = bk.read_rr_now();
  }
  if (!std::isfinite(bnorm2))
    throw NumericalError("solver: the right-hand side (or the matrix) is not finite");
  if (bnorm2 == 0) {  // the solution is x_fixed and zero elsewhere
    std::copy(xc.begin(), xc.end(), x);
    return st;
  }
  const double tol = opt.relative_tolerance;
  const double tol2 = tol * tol * bnorm2;
  bk.upload(VX, x);
  auto true_residual = [&] {  // VR = residual (normal eqs for paper); returns its squared norm
    if (normal) {
      bk.residual(VTMP, VB, VX);
      bk.spmv(VR, VTMP, true);
    } else {
      bk.residual(VR, VB, VX);
    }
    bk.dot(VR, VR, OP_NORM);
    return bk.read_rr_now();
  };
  double rr_true = true_residual();
  for (int attempt = 0;; ++attempt) {
    double rr = 0;
    st.iterations += krylov(bk, opt.method, tol2, opt.max_iterations - st.iterations, &rr, bnorm2, tol);
    rr_true = true_residual();  // the recursive residual can drift from the true one
    if (rr_true <= tol2) break;
    if (attempt == 3 || st.iterations >= opt.max_iterations)
      not_converged(opt.method, std::sqrt(rr_true / bnorm2), st.iterations, tol, n,
                    "did not converge (true residual above tolerance after restarts)");
  }
  bk.download(VX, x);
  if (normal) {
    bk.residual(VTMP, VB, VX);
    bk.dot(VTMP, VTMP, OP_NORM);
    st.relative_residual = std::sqrt(bk.read_rr_now() / borig2);
  } else {
    st.relative_residual = std::sqrt(rr_true / bnorm2);
  }
  return st;
}

}  // namespace vpm::detail
