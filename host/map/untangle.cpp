// Garanzha et al. 2021 untangler: L-BFGS at fixed eps and the eps schedule, global and local
// (see vpm/untangle.hpp; the energy in map/untangle_energy.cpp and map/untangle_device.cpp).
#include "vpm/untangle.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <deque>
#include <memory>
#include <string>

#include "map/untangle_problem.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace {

using Problem = UntangleProblem;
using Eval = UntangleEval;

void scatter(const Problem& p, const Eigen::VectorXd& z, Points& x) {
  for (int v : p.free_vertices) {
    const int i = p.var[v];
    x.row(v) << z(i), z(i + 1), z(i + 2);
  }
}

Eigen::VectorXd gather(const Problem& p, const Points& x) {
  Eigen::VectorXd z(3 * p.free_vertices.size());
  for (int v : p.free_vertices) {
    const int i = p.var[v];
    z(i) = x(v, 0);
    z(i + 1) = x(v, 1);
    z(i + 2) = x(v, 2);
  }
  return z;
}

// L-BFGS memory: the last correction pairs (s, y) and rho = 1 / s.y.
struct LbfgsMemory {
  std::deque<Eigen::VectorXd> S, Y;
  std::deque<double> rho;
  bool empty() const { return S.empty(); }
  void clear() {
    S.clear();
    Y.clear();
    rho.clear();
  }
  void push(Eigen::VectorXd s, Eigen::VectorXd y, int capacity) {
    const double sy = s.dot(y);
    if (!(sy > 1e-300)) return;
    S.push_back(std::move(s));
    Y.push_back(std::move(y));
    rho.push_back(1.0 / sy);
    if (static_cast<int>(S.size()) > capacity) {
      S.pop_front();
      Y.pop_front();
      rho.pop_front();
    }
  }
};

// Search direction by the two-loop recursion; the first step (empty memory) moves the fastest
// vertex by a small fraction of the mesh scale.
Eigen::VectorXd lbfgs_direction(const LbfgsMemory& mem, const Eigen::VectorXd& g, const Eigen::VectorXd& z) {
  Eigen::VectorXd q = -g;
  std::vector<double> alpha(mem.S.size());
  for (int k = static_cast<int>(mem.S.size()) - 1; k >= 0; --k) {
    alpha[k] = mem.rho[k] * mem.S[k].dot(q);
    q -= alpha[k] * mem.Y[k];
  }
  if (!mem.empty()) {
    q *= mem.S.back().dot(mem.Y.back()) / mem.Y.back().squaredNorm();
  } else {
    const double gi = g.lpNorm<Eigen::Infinity>();
    double scale = 0;
    for (Eigen::Index k = 0; k < z.size(); ++k) scale = std::max(scale, std::abs(z(k)));
    q *= (gi > 0 ? 1e-3 * std::max(scale, 1e-12) / gi : 0.0);
  }
  for (size_t k = 0; k < mem.S.size(); ++k) {
    const double b = mem.rho[k] * mem.Y[k].dot(q);
    q += (alpha[k] - b) * mem.S[k];
  }
  return q;
}

// Backtracking (Armijo) line search from z0 along q: on success z, x, en and gn hold the new
// point; on failure z and x are back at z0.
bool line_search(const Problem& p, Points& x, double eps, const Eigen::VectorXd& z0, const Eigen::VectorXd& q,
                 double e, double slope, Eigen::VectorXd& z, double& en, Eigen::VectorXd& gn, int* evals) {
  double step = 1.0;
  for (int ls = 0; ls < 40; ++ls) {
    z = z0 + step * q;
    scatter(p, z, x);
    en = evaluate(p, x, eps, &gn).energy;
    ++*evals;
    if (std::isfinite(en) && en <= e + 1e-4 * step * slope) return true;
    step *= 0.5;
  }
  z = z0;
  scatter(p, z, x);
  return false;
}

// L-BFGS with backtracking line search at fixed eps. Returns iterations run.
int lbfgs(const Problem& p, Points& x, double eps, const UntangleOptions& o, int* evals, Clock::time_point deadline) {
  const int nz = static_cast<int>(3 * p.free_vertices.size());
  if (nz == 0) return 0;
  Eigen::VectorXd z = gather(p, x), g(nz), gn(nz);
  double e = evaluate(p, x, eps, &g).energy;
  ++*evals;
  const double g0 = g.lpNorm<Eigen::Infinity>();
  LbfgsMemory mem;
  int it = 0;
  for (; it < o.max_lbfgs_iterations; ++it) {
    if (g.lpNorm<Eigen::Infinity>() <= o.gradient_tolerance * (1 + g0)) break;
    if (o.max_seconds > 0 && Clock::now() > deadline) break;
    Eigen::VectorXd q = lbfgs_direction(mem, g, z);
    double slope = g.dot(q);
    if (!(slope < 0)) {  // not a descent direction: restart with steepest descent
      mem.clear();
      q = -g * (1e-3 / std::max(g.lpNorm<Eigen::Infinity>(), 1e-300));
      slope = g.dot(q);
      if (!(slope < 0)) break;
    }
    double en = 0;
    const Eigen::VectorXd z0 = z;
    if (!line_search(p, x, eps, z0, q, e, slope, z, en, gn, evals)) {
      if (mem.empty()) break;  // even a steepest-descent step fails: converged to precision
      mem.clear();
      continue;
    }
    mem.push(z - z0, gn - g, o.lbfgs_memory);
    const double de = e - en;
    e = en;
    g.swap(gn);
    if (de <= o.energy_tolerance * std::max(std::abs(e), 1e-300)) {
      ++it;
      break;
    }
  }
  return it;
}

// Reference edge matrices (scaled so the active tets' volume matches x's when asked) and
// weights of the active tets.
void prepare_reference(Problem& p, const Points& reference, const Tets& tets, const Points& x,
                       const UntangleOptions& o) {
  double vref = 0, vx = 0;
  std::vector<Eigen::Matrix3d> R(p.active.size());
  for (size_t a = 0; a < p.active.size(); ++a) {
    const int ti = p.active[a];
    Eigen::Matrix3d E, X;
    for (int k = 0; k < 3; ++k) {
      E.col(k) = (reference.row(tets(ti, k + 1)) - reference.row(tets(ti, 0))).transpose();
      X.col(k) = (x.row(tets(ti, k + 1)) - x.row(tets(ti, 0))).transpose();
    }
    R[a] = E;
    vref += E.determinant() / 6.0;
    vx += X.determinant() / 6.0;
  }
  if (!(vref > 0))
    throw InputError("untangle: reference tets have non-positive total volume " + std::to_string(vref));
  double scale = 1.0;
  if (o.rescale_reference && vx > 0) scale = std::cbrt(vx / vref);
  p.rinv.resize(p.active.size());
  p.weight.resize(p.active.size());
  for (size_t a = 0; a < p.active.size(); ++a) {
    const double vol = R[a].determinant() / 6.0;
    if (!(vol > 0))
      throw InputError("untangle: reference tet " + std::to_string(p.active[a]) +
                       " is not positively oriented (volume " + std::to_string(vol) + ")");
    p.rinv[a] = (scale * R[a]).inverse();
    p.weight[a] = vol / vref;
  }
}

// The paper's floor of sigma in the eps update.
constexpr double kPaperSigmaMin = 0.1;

// The outer loop: one L-BFGS minimisation per eps, eps updated from the smallest det J.
void minimise(const Problem& p, Points& x, const UntangleOptions& o, Clock::time_point t0, UntangleResult& r) {
  Eval ev = evaluate(p, x, 1.0, nullptr);
  r.min_det_before = ev.min_det;
  double d_prev = ev.min_det;
  double eps = std::sqrt(1e-12 + 0.04 * std::pow(std::min(ev.min_det, 0.0), 2));
  double e_prev = evaluate(p, x, eps, nullptr).energy;
  r.energy_before = e_prev;
  int evals = 0;
  const auto deadline =
      t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::max(o.max_seconds, 0.0)));
  for (int outer = 0; outer < o.max_outer_iterations; ++outer) {
    if (o.max_seconds > 0 && Clock::now() > deadline) {
      r.out_of_time = true;
      break;
    }
    r.lbfgs_iterations += lbfgs(p, x, eps, o, &evals, deadline);
    ++r.iterations;
    ev = evaluate(p, x, eps, nullptr);
    const double e = ev.energy;
    r.energy_after = e;
    r.final_eps = eps;
    // a fold that the minimisation hardly moved (Dmin <= 0, raised by under a tenth) takes the
    // stalled floor of sigma; progress keeps the paper's
    const bool stalled = ev.min_det <= 0 && ev.min_det < d_prev + 0.1 * std::abs(d_prev);
    eps = untangle_next_eps(e, e_prev, ev.min_det, eps, stalled ? o.stalled_sigma_min : kPaperSigmaMin);
    d_prev = ev.min_det;
    if (ev.min_det > 0 && (o.stop_when_untangled || std::abs(e_prev - e) <= o.outer_energy_tolerance * std::abs(e)))
      break;
    e_prev = e;
  }
  r.min_det_after = evaluate(p, x, 1.0, nullptr).min_det;
  r.evaluations = evals;
}

UntangleResult run(Problem& p, const Points& reference, const Tets& tets, Points& x, const UntangleOptions& o,
                   Device* device) {
  const auto t0 = Clock::now();
  UntangleResult r;
  r.inverted_before = static_cast<int>(inverted_tets(x, tets).size());
  p.tets = &tets;
  p.theta = o.theta;
  r.free_vertices = static_cast<int>(p.free_vertices.size());
  r.active_tets = static_cast<int>(p.active.size());
  if (p.active.empty()) {
    r.inverted_tets = inverted_tets(x, tets);
    r.inverted_after = static_cast<int>(r.inverted_tets.size());
    return r;
  }
  prepare_reference(p, reference, tets, x, o);
  std::unique_ptr<UntangleDeviceEval> dev_eval;
  std::unique_ptr<UntangleHostEval> host_eval;
  if (device && !device->is_host()) {
    dev_eval = std::make_unique<UntangleDeviceEval>(*device, p, static_cast<int>(x.rows()));
    p.device = dev_eval.get();
  } else {
    host_eval = std::make_unique<UntangleHostEval>(p);
    p.host = host_eval.get();
  }
  const Points given = x;
  minimise(p, x, o, t0, r);
  p.device = nullptr;
  p.host = nullptr;
  r.inverted_tets = inverted_tets(x, tets);
  r.inverted_after = static_cast<int>(r.inverted_tets.size());
  if (r.inverted_after > r.inverted_before) {  // never hand back more folds than were given
    x = given;
    r.kept_input = true;
    r.inverted_tets = inverted_tets(x, tets);
    r.inverted_after = static_cast<int>(r.inverted_tets.size());
    r.min_det_after = r.min_det_before;
    r.energy_after = r.energy_before;
  }
  r.seconds = seconds_since(t0);
  return r;
}

void check_sizes(const Points& reference, const Tets& tets, const Points& x,
                 const std::vector<char>& fixed) {
  if (reference.rows() != x.rows() || static_cast<Eigen::Index>(fixed.size()) != x.rows())
    throw InputError("untangle: reference (" + std::to_string(reference.rows()) + "), x (" +
                     std::to_string(x.rows()) + ") and fixed (" + std::to_string(fixed.size()) +
                     ") must have one row per vertex");
  const int n = static_cast<int>(x.rows());
  for (Eigen::Index i = 0; i < tets.rows(); ++i)
    for (int c = 0; c < 4; ++c)
      if (tets(i, c) < 0 || tets(i, c) >= n)
        throw InputError("untangle: tet " + std::to_string(i) + " has vertex index " +
                         std::to_string(tets(i, c)) + " out of range");
}

}  // namespace

std::vector<int> inverted_tets(const Points& x, const Tets& tets) {
  const Eigen::VectorXd v = tet_volumes(x, tets);
  std::vector<int> out;
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (!(v(i) > 0)) out.push_back(static_cast<int>(i));
  return out;
}

UntangleOptions untangle_local_options() {
  UntangleOptions o;
  o.theta = 0.5;
  o.stalled_sigma_min = 0.5;
  return o;
}

UntangleResult untangle(const Points& reference, const Tets& tets, Points& x,
                        const std::vector<char>& fixed, const UntangleOptions& options) {
  return untangle(*Device::host(), reference, tets, x, fixed, options);
}

UntangleResult untangle_local(const Points& reference, const Tets& tets, Points& x,
                              const std::vector<char>& fixed, const std::vector<int>& folded,
                              int rings, const UntangleOptions& options) {
  return untangle_local(*Device::host(), reference, tets, x, fixed, folded, rings, options);
}

namespace {
// The unknowns of a run: the vertices with `chosen` set and not fixed (in vertex order), and the
// tets that have one of them (in tet order).
Problem problem_of(const Tets& tets, int n, const std::vector<char>& fixed, const std::vector<char>& chosen) {
  Problem p;
  p.var.assign(n, -1);
  for (int v = 0; v < n; ++v)
    if (chosen[static_cast<size_t>(v)] && !fixed[v]) {
      p.var[v] = static_cast<int>(3 * p.free_vertices.size());
      p.free_vertices.push_back(v);
    }
  for (Eigen::Index i = 0; i < tets.rows(); ++i) {
    bool any = false;
    for (int c = 0; c < 4; ++c) any = any || p.var[tets(i, c)] >= 0;
    if (any) p.active.push_back(static_cast<int>(i));
  }
  return p;
}
}  // namespace

UntangleResult untangle(Device& device, const Points& reference, const Tets& tets, Points& x,
                        const std::vector<char>& fixed, const UntangleOptions& options) {
  check_sizes(reference, tets, x, fixed);
  const int n = static_cast<int>(x.rows());
  // only vertices used by some tet are unknowns
  std::vector<char> used(n, 0);
  for (Eigen::Index i = 0; i < tets.rows(); ++i)
    for (int c = 0; c < 4; ++c) used[tets(i, c)] = 1;
  Problem p = problem_of(tets, n, fixed, used);
  return run(p, reference, tets, x, options, &device);
}

UntangleResult untangle_local(Device& device, const Points& reference, const Tets& tets, Points& x,
                              const std::vector<char>& fixed, const std::vector<int>& folded,
                              int rings, const UntangleOptions& options) {
  check_sizes(reference, tets, x, fixed);
  const int n = static_cast<int>(x.rows());
  for (int t : folded)
    if (t < 0 || t >= tets.rows())
      throw InputError("untangle_local: folded tet index " + std::to_string(t) + " out of range");
  const std::vector<char> near = vertices_near_tets(n, tets, folded, rings);
  Problem p = problem_of(tets, n, fixed, near);
  return run(p, reference, tets, x, options, &device);
}

Json to_json(const UntangleResult& r) {
  Json j = Json::object();
  j["inverted_before"] = r.inverted_before;
  j["inverted_after"] = r.inverted_after;
  j["iterations"] = r.iterations;
  j["lbfgs_iterations"] = r.lbfgs_iterations;
  j["evaluations"] = r.evaluations;
  j["free_vertices"] = r.free_vertices;
  j["active_tets"] = r.active_tets;
  j["min_det_before"] = r.min_det_before;
  j["min_det_after"] = r.min_det_after;
  j["energy_before"] = r.energy_before;
  j["energy_after"] = r.energy_after;
  j["final_eps"] = r.final_eps;
  j["seconds"] = r.seconds;
  j["out_of_time"] = r.out_of_time;
  j["kept_input"] = r.kept_input;
  Json list = Json::array();
  for (size_t i = 0; i < r.inverted_tets.size() && i < 20; ++i) list.push_back(r.inverted_tets[i]);
  j["inverted_tets_first"] = list;
  return j;
}

}  // namespace vpm
