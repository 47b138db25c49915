// The round loops of the volume-preserving map (map/volume_map_context.hpp): Moser rounds
// (or the paper's steps, or vsem iterations), each fold-checked, then the polish rounds.
#include <algorithm>
#include <cmath>
#include <string>

#include "map/volume_map_context.hpp"
#include "vpm/format.hpp"
#include "vpm/geometry.hpp"
#include "vpm/timing.hpp"

namespace vpm::detail {

namespace {

int round_cap(const MapContext& c) {
  const VolumeMapOptions& opt = c.opt;
  if (c.pc.only) return 0;
  if (opt.rounds >= 0) return opt.rounds;
  if (opt.max_rounds > 0) return opt.max_rounds;
  if (c.rounds == Rounds::moser) return 8;
  if (c.rounds == Rounds::paper) return c.paper_steps;
  return 15;
}

// vsem: weights *= current normalised tet volume ratio; the harmonic map of the reweighted
// stiffness with the boundary frozen is the round's target.
Points vsem_target(MapContext& c, const Points& x, Eigen::VectorXd& w, VolumeMapRound& r) {
  const Eigen::VectorXd v1 = tet_volumes(x, c.tets);
  const Eigen::VectorXd ratio = (v1 / v1.sum()).array() / c.ref_tet.array();
  w.array() *= ratio.array().max(1e-6);
  w /= w.mean();
  const auto t0 = Clock::now();
  const auto K = weighted_stiffness(c.ref, c.tets, &w);
  Points target = x;
  const SolveStats s = c.solver->dirichlet(K, c.boundary, target);
  r.solver_iterations = s.iterations;
  r.solver_residual = s.residual;
  r.time_solve += seconds_since(t0);
  return target;
}

// A step that folds more than this fraction of the tets is not untangled but shortened first
// (untangling thousands of folds takes tens of seconds at 30k tets and gives the step's gain
// back: the coil of bench/shapes folded 12 % per polish step, docs/shapes.md).
constexpr double kUntangleMaxFoldFraction = 0.05;

// Moves x from `saved` by move(attempt, step) and checks it: a move that folds is untangled
// locally (unless it folds more than kUntangleMaxFoldFraction), and if folds remain it is tried
// again with the step halved, up to `max_attempts` more times. r.folds_before_untangle counts
// the folds of every attempt (`each_attempt`) or of the first; r.t_end is the step used.
// Returns the folds left (0: accepted).

template <class Move>
int fold_free(MapContext& c, Points& x, const Points& saved, double step, int max_attempts, bool each_attempt,
              VolumeMapRound& r, Move move) {
  int folds = 0;
  for (int attempt = 0; attempt <= max_attempts; ++attempt) {
    move(attempt, step);
    folds = count_folds(c, x);
    if (each_attempt || attempt == 0) r.folds_before_untangle = folds;
    r.t_end = step;
    if (folds > kUntangleMaxFoldFraction * c.m) {  // left as folded: counts as not repaired
      step *= 0.5;
      continue;
    }
    if (folds > 0) {
      r.untangled = c.opt.local_untangle;
      folds = untangle_folds(c, x, &r.time_untangle, &saved);
    }
    r.t_end = step;
    if (folds == 0) break;
    step *= 0.5;
  }
  return folds;
}

// One round from `saved` on [0, t_end] (t_end halved while it folds beyond repair).
int fold_free_round(MapContext& c, Points& x, const Points& saved, double t_end, const Points& vsem_goal,
                    VolumeMapRound& r) {
  return fold_free(c, x, saved, t_end, c.opt.max_step_halvings, true, r, [&](int attempt, double step) {
    if (attempt > 0) x = saved;
    if (c.rounds == Rounds::moser) {
      moser_round(c, x, step, r);
    } else if (c.rounds == Rounds::paper) {
      paper_step(c, x, step, r);
    } else {
      x = saved + step * (vsem_goal - saved);
    }
  });
}

void add_times(VolumeMapTimings& t, const VolumeMapRound& r) {
  t.solve += r.time_solve;
  t.field += r.time_field;
  t.advect += r.time_advect;
  t.untangle += r.time_untangle;
}

void say_round(const MapContext& c, int k, int max_rounds, const DistortionPair& d, const VolumeMapRound& r) {
  if (!c.opt.progress) return;
  std::string line = std::string(to_string(c.rounds)) + " round " + std::to_string(k) + "/" +
                     std::to_string(max_rounds) +
                     strprintf(": vertex mean |r-1| %.4f, tet %.4f, %.2f s", d.vertex, d.tet, r.time_total);
  if (r.folds_before_untangle)
    line += ", folds " + std::to_string(r.folds_before_untangle) + (r.discarded ? " (round discarded)" : " (untangled)");
  c.opt.progress(line);
}

// Automatic stop: hand over to the polish rounds once the distortion is within 5x the tolerance
// (a polish step removes the last few percent for a third of a round's time, and a second round
// from there leaves the same map after the polish: brains from 26k to 1.1M tets, the kidney;
// far from the goal, as on a C-shaped caudate at 9 %, more rounds still pay), or when a round
// gains less than a fifth.
bool stalled(const MapContext& c, double vertex, double prev_vertex) {
  const VolumeMapOptions& opt = c.opt;
  return opt.rounds < 0 && c.rounds == Rounds::moser && opt.polish_rounds > 0 &&
         vertex > opt.tolerance && (vertex <= 5 * opt.tolerance || vertex > 0.8 * prev_vertex);
}

}  // namespace

void run_rounds(MapContext& c, Points& x, VolumeMapResult& res, DistortionPair& d) {
  const VolumeMapOptions& opt = c.opt;
  const int max_rounds = round_cap(c);
  res.stop_reason = c.pc.only ? "polish_only" : "rounds";
  double paper_dt = 1.0 / std::max(1, c.paper_steps);
  Eigen::VectorXd vsem_w = Eigen::VectorXd::Ones(c.m);
  double prev_vertex = d.vertex;
  for (int k = 1; k <= max_rounds; ++k) {
    if (opt.rounds < 0 && d.vertex <= opt.tolerance) {
      res.stop_reason = "tolerance";
      break;
    }
    if (opt.deadline.passed()) {
      res.stop_reason = "time_budget";
      break;
    }
    const auto t_round = Clock::now();
    VolumeMapRound r;
    r.round = k;
    r.kind = to_string(c.rounds);
    const Points saved = x;
    Points vsem_goal;
    if (c.rounds == Rounds::vsem) vsem_goal = vsem_target(c, x, vsem_w, r);
    const double t_end = c.rounds == Rounds::paper ? paper_dt : 1.0;
    const int folds = fold_free_round(c, x, saved, t_end, vsem_goal, r);
    r.folds = 0;
    if (folds > 0) {  // not repairable: undo the round
      x = saved;
      r.discarded = true;
    }
    if (c.rounds == Rounds::paper && !r.discarded) paper_dt = r.t_end;
    d = volume_distortion(c.ref, x, c.tets);
    r.vertex_mean_abs_dev = d.vertex;
    r.tet_mean_abs_dev = d.tet;
    r.time_total = seconds_since(t_round);
    add_times(res.timings, r);
    res.rounds.push_back(r);
    say_round(c, k, max_rounds, d, r);
    if (r.discarded) {
      res.stop_reason = "fold";
      break;
    }
    if (stalled(c, d.vertex, prev_vertex)) {
      res.stop_reason = "stalled";
      break;
    }
    prev_vertex = d.vertex;
  }
  if (res.stop_reason == "rounds" && opt.rounds < 0 && d.vertex <= opt.tolerance) res.stop_reason = "tolerance";
  c.field = MoserField{};  // the polish rounds do not need its memory
}

namespace {

// A polish step that folds is untangled, but untangling a handful of folds can give back the
// whole step's gain (on the hand of bench/shapes one fold's untangling took the vertex mean
// |r-1| from 1.2 % to 2.7 %, and the polish stalled there): the shorter steps down to this
// fraction are tried too, and the longest that does not fold replaces the untangled step when it
// leaves less tet distortion (bench/results/LEDGER.md).
constexpr double kPolishShortestStep = 0.25;

// The polish direction dx applied from `saved` (the step halved while it folds beyond repair;
// a shorter fold-free step preferred to an untangled one that distorts more).
int fold_free_polish(MapContext& c, Points& x, const Points& saved, const Points& dx, VolumeMapRound& r) {
  const auto apply = [&](Points& y, double step) {
    y = saved + step * dx;
    project_boundary(c, y);
  };
  const int folds = fold_free(c, x, saved, 1.0, c.opt.max_step_halvings + 2, false, r,
                              [&](int, double step) { apply(x, step); });
  if (r.folds_before_untangle == 0) return folds;
  Points shorter;
  for (double step = 0.5 * r.t_end; step >= kPolishShortestStep; step *= 0.5) {
    apply(shorter, step);
    if (count_folds(c, shorter) > 0) continue;
    if (folds > 0 || volume_distortion(c.ref, shorter, c.tets).tet < volume_distortion(c.ref, x, c.tets).tet) {
      x.swap(shorter);
      r.t_end = step;
      return 0;
    }
    break;
  }
  return folds;
}

}  // namespace

// Once the map meets its tolerance, a polish round must bring the tet mean |r-1| 3 % lower for
// another to follow (before: VolumeMapOptions::polish_min_gain, 1 % by default).
constexpr double kPolishKeepConverged = 0.97;
// Short of the tolerance, the polish goes on past VolumeMapOptions::polish_rounds while each round
// still lowers the tet mean |r-1| by a tenth, up to this many times polish_rounds: long thin
// parts, which the Moser rounds leave far from it, gain 20-40 % a round through the first 8 (a
// long bone's shaft; bench/results/LEDGER.md).
constexpr int kPolishExtension = 4;
constexpr double kPolishKeepFar = 0.9;

void run_polish(MapContext& c, Points& x, VolumeMapResult& res, DistortionPair& d) {
  const VolumeMapOptions& opt = c.opt;
  const int n_polish = c.rounds == Rounds::moser && opt.rounds != 0 ? opt.polish_rounds : 0;
  // when the Moser rounds stalled far from the tolerance (long thin parts such as fingers), a
  // longer CGLS: early-stopped, it only reaches the smooth part of the correction, and on a finer
  // mesh the same correction spans more elements (cube root of the tet count past 30,000)
  const int far = polish_iterations_for(opt.polish_iterations_far, c.m);
  const int iterations = !c.pc.only && d.vertex > 5 * opt.tolerance ? std::max(opt.polish_iterations, far)
                                                                             : opt.polish_iterations;
  int cap = n_polish;
  for (int k = 1; k <= cap; ++k) {
    if (opt.deadline.passed()) {
      res.stop_reason = "time_budget";
      break;
    }
    const double tet_before = d.tet;
    const auto t_round = Clock::now();
    VolumeMapRound r;
    r.round = static_cast<int>(res.rounds.size()) + 1;
    r.kind = "polish";
    const Points saved = x;
    Points dx;
    polish_step(c, x, r, dx, iterations);
    const auto t2 = Clock::now();
    const int folds = fold_free_polish(c, x, saved, dx, r);
    r.time_advect += seconds_since(t2) - r.time_untangle;
    const DistortionPair dp = volume_distortion(c.ref, x, c.tets);
    const bool converged = !c.pc.only && dp.vertex <= opt.tolerance;
    const bool no_gain = dp.tet > (converged ? kPolishKeepConverged : 1.0 - opt.polish_min_gain) * d.tet;
    if (folds > 0 || dp.tet >= d.tet) {  // no progress or folded: undo and stop polishing
      x = saved;
      r.discarded = true;
    } else {
      d = dp;
    }
    r.folds = 0;
    r.vertex_mean_abs_dev = d.vertex;
    r.tet_mean_abs_dev = d.tet;
    r.time_total = seconds_since(t_round);
    res.timings.solve += r.time_solve;
    res.timings.advect += r.time_advect;
    res.timings.untangle += r.time_untangle;
    res.rounds.push_back(r);
    if (opt.progress)
      opt.progress("polish " + std::to_string(k) + "/" + std::to_string(cap) +
                   strprintf(": vertex mean |r-1| %.4f, tet %.4f, %.2f s", d.vertex, d.tet, r.time_total) +
                   (r.discarded ? " (discarded)" : ""));
    if (r.discarded || no_gain) break;
    if (k == cap && !converged && cap < kPolishExtension * n_polish && d.tet < kPolishKeepFar * tet_before) ++cap;
  }
}

}  // namespace vpm::detail
