#pragma once
// Private: Jacobi CG on up to kMaxBlock right-hand sides with one matrix (the three coordinates
// of a harmonic map). Each column has its own backend (vectors and scalars) and runs exactly the
// iterations of solve_system (linalg/krylov.hpp) alone, so its result is the same bit for bit;
// what the columns share is the sparse product: one spmv_block reads the matrix once for all
// (memory-bound, it is most of an iteration's time).
#include <algorithm>
#include <vector>

#include "linalg/krylov.hpp"

namespace vpm::detail {

// The first Krylov run of krylov() (Jacobi CG) for every column in lockstep: VX holds each
// start and VR its residual (solve_begin). Each column keeps its own KrylovPace, so it takes the
// iterations of a lone run; adds them to its stats.
template <class BK>
void krylov_block(const std::vector<BK*>& bks, const std::vector<SolveState*>& states, int max_iterations) {
  const size_t k = bks.size();
  std::vector<KrylovPace> pace;
  for (size_t c = 0; c < k; ++c) {
    const SolveState& s = *states[c];
    pace.push_back({SolverMethod::cg, s.tol2, s.bnorm2, s.tol, bks[c]->size(), max_iterations, bks[c]->lookahead()});
    bks[c]->cg_init();
    pace[c].start(bks[c]->read_rr_now());
  }
  while (std::any_of(pace.begin(), pace.end(), [](const KrylovPace& p) { return !p.finished; })) {
    for (;;) {  // queue as krylov() does, one product for the columns that queue an iteration
      std::vector<BK*> step;
      std::vector<size_t> which;
      for (size_t c = 0; c < k; ++c)
        if (pace[c].may_enqueue()) {
          step.push_back(bks[c]);
          which.push_back(c);
        }
      if (step.empty()) break;
      BK::spmv_block(step.data(), static_cast<int>(step.size()), VQ, VP);
      for (size_t q = 0; q < step.size(); ++q) {
        step[q]->dot(VP, VQ, OP_CG_ALPHA);
        step[q]->cg_update_xr();
        step[q]->cg_update_p();
        step[q]->request_rr(pace[which[q]].enqueue());
      }
    }
    for (size_t c = 0; c < k; ++c)  // then one read per running column
      if (!pace[c].finished && pace[c].read(bks[c]->wait_rr(pace[c].next_read())))
        states[c]->stats.iterations += pace[c].done;
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
  std::vector<SolveState*> running_states;
  std::vector<size_t> index;
  for (size_t c = 0; c < k; ++c)
    if (solve_begin(*bks[c], opt, mask, b[c], x[c], states[c])) {
      running.push_back(bks[c]);
      running_states.push_back(&states[c]);
      index.push_back(c);
    }
  if (!running.empty()) krylov_block(running, running_states, opt.max_iterations);
  for (size_t q = 0; q < running.size(); ++q) {
    solve_runs(*running[q], opt, *running_states[q], 1);
    solve_end(*running[q], x[index[q]], *running_states[q]);
  }
  std::vector<SolverStats> out;
  for (const SolveState& s : states) out.push_back(s.stats);
  return out;
}

}  // namespace vpm::detail
