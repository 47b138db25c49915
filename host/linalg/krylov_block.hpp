#pragma once
// Private: Jacobi CG on up to kMaxBlock right-hand sides with one matrix (the three coordinates
// of a harmonic map). Each column has its own backend (vectors and scalars) and runs exactly the
// iterations of solve_system (linalg/krylov.hpp) alone, so its result is the same bit for bit;
// what the columns share is the sparse product: one spmv_block reads the matrix once for all
// (memory-bound, it is most of an iteration's time).
#include <vector>

#include "linalg/krylov.hpp"

namespace vpm::detail {

// One column's place in the loop of krylov() (the same decisions, column by column).
struct BlockColumn {
  int enqueued = 0, done = 0;
  bool stop = false, finished = false;
};

// The first Krylov run of krylov() (Jacobi CG) for every column in lockstep: VX holds each
// start and VR its residual (solve_begin). Adds each column's iterations to its stats.
template <class BK>
void krylov_block(const std::vector<BK*>& bks, std::vector<SolveState>& states, int max_iterations) {
  const int k = static_cast<int>(bks.size());
  std::vector<BlockColumn> col(static_cast<size_t>(k));
  for (int c = 0; c < k; ++c) {
    BK& bk = *bks[static_cast<size_t>(c)];
    const SolveState& s = states[static_cast<size_t>(c)];
    bk.cg_init();
    const double rr = bk.read_rr_now();
    if (!std::isfinite(rr))
      not_converged(SolverMethod::cg, rr, 0, s.tol, bk.size(), "started from a non-finite residual");
    col[static_cast<size_t>(c)].finished = rr <= s.tol2;
    if (!col[static_cast<size_t>(c)].finished && max_iterations <= 0)
      not_converged(SolverMethod::cg, std::sqrt(rr / s.bnorm2), 0, s.tol, bk.size(), "did not converge");
  }
  const int lookahead = bks[0]->lookahead();
  auto eligible = [&](const BlockColumn& b) {
    return !b.finished && !b.stop && b.enqueued < max_iterations && b.enqueued < b.done + lookahead;
  };
  for (;;) {
    bool any = false;
    for (const BlockColumn& b : col) any = any || !b.finished;
    if (!any) return;
    for (;;) {  // enqueue, as krylov() does, batching the product over the columns
      std::vector<BK*> step;
      std::vector<int> which;
      for (int c = 0; c < k; ++c)
        if (eligible(col[static_cast<size_t>(c)])) {
          step.push_back(bks[static_cast<size_t>(c)]);
          which.push_back(c);
        }
      if (step.empty()) break;
      BK::spmv_block(step.data(), static_cast<int>(step.size()), VQ, VP);
      for (size_t q = 0; q < step.size(); ++q) {
        BK& bk = *step[q];
        BlockColumn& b = col[static_cast<size_t>(which[q])];
        bk.dot(VP, VQ, OP_CG_ALPHA);
        bk.cg_update_xr();
        bk.cg_update_p();
        bk.request_rr(b.enqueued % 2);
        ++b.enqueued;
      }
    }
    for (int c = 0; c < k; ++c) {  // then one read per running column
      BlockColumn& b = col[static_cast<size_t>(c)];
      if (b.finished) continue;
      BK& bk = *bks[static_cast<size_t>(c)];
      SolveState& s = states[static_cast<size_t>(c)];
      const double rr = bk.wait_rr(b.done % 2);
      ++b.done;
      if (!std::isfinite(rr))
        not_converged(SolverMethod::cg, rr, b.done, s.tol, bk.size(), "broke down (non-finite residual)");
      if (rr <= s.tol2) {
        if (b.done == b.enqueued) {
          b.finished = true;
          s.stats.iterations += b.done;
        } else {
          b.stop = true;  // the iteration already queued gives the result
        }
      } else if (b.done == b.enqueued) {
        b.stop = false;
        if (b.done >= max_iterations)
          not_converged(SolverMethod::cg, std::sqrt(rr / s.bnorm2), b.done, s.tol, bk.size(), "did not converge");
      }
    }
  }
}

// solve_system for k <= kMaxBlock right-hand sides on k backends that hold the same matrix and
// mask (Jacobi CG only: opt.method cg, no multigrid). b[c], x[c] as in solve_system.
template <class BK>
std::vector<SolverStats> solve_system_block(const std::vector<BK*>& bks, const SolverOptions& opt,
                                            const std::vector<char>& mask, const std::vector<const double*>& b,
                                            const std::vector<double*>& x) {
  const size_t k = bks.size();
  std::vector<SolveState> states(k);
  std::vector<BK*> running;
  std::vector<SolveState> running_states;
  std::vector<size_t> index;
  for (size_t c = 0; c < k; ++c)
    if (solve_begin(*bks[c], opt, mask, b[c], x[c], states[c])) {
      running.push_back(bks[c]);
      running_states.push_back(states[c]);
      index.push_back(c);
    }
  if (!running.empty()) krylov_block(running, running_states, opt.max_iterations);
  for (size_t q = 0; q < running.size(); ++q) {
    SolveState& s = running_states[q];
    solve_runs(*running[q], opt, s, 1);
    solve_end(*running[q], x[index[q]], s);
    states[index[q]] = s;
  }
  std::vector<SolverStats> out;
  for (const SolveState& s : states) out.push_back(s.stats);
  return out;
}

}  // namespace vpm::detail
