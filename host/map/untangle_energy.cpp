// Host evaluation of the untangling energy and gradient (see map/untangle_problem.hpp).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include "map/untangle_problem.hpp"

namespace vpm {

namespace detail {
// a tet's energy and the factors of its gradient, shared with kernels/untangle.cl
#include "kernels/untangle_energy.clh"
}  // namespace detail

namespace {

// Energy (and gradient if g != nullptr, zeroed first) over active tets [begin, end).
UntangleEval evaluate_range(const UntangleProblem& p, const Points& x, double eps, Eigen::VectorXd* g, size_t begin,
                    size_t end) {
  UntangleEval out;
  out.min_det = std::numeric_limits<double>::infinity();
  if (g) g->setZero();
  const Tets& t = *p.tets;
  const double th = p.theta;
  for (size_t a = begin; a < end; ++a) {
    const int ti = p.active[a];
    const int v0 = t(ti, 0), v1 = t(ti, 1), v2 = t(ti, 2), v3 = t(ti, 3);
    Eigen::Matrix3d X;
    X.col(0) = (x.row(v1) - x.row(v0)).transpose();
    X.col(1) = (x.row(v2) - x.row(v0)).transpose();
    X.col(2) = (x.row(v3) - x.row(v0)).transpose();
    const Eigen::Matrix3d J = X * p.rinv[a];
    Eigen::Matrix3d C;  // cofactor matrix: d det / d J
    C.col(0) = J.col(1).cross(J.col(2));
    C.col(1) = J.col(2).cross(J.col(0));
    C.col(2) = J.col(0).cross(J.col(1));
    const double d = J.col(0).dot(C.col(0));
    out.min_det = std::min(out.min_det, d);
    if (d <= 0) ++out.nonpositive;
    double k1, k2;
    const double f = detail::ue_energy(d, J.squaredNorm(), eps, th, &k1, &k2);
    const double w = p.weight[a];
    out.energy += w * f;
    if (!g) continue;
    const Eigen::Matrix3d G = (w * (k1 * J + k2 * C)) * p.rinv[a].transpose();  // dE/dX
    const int vs[4] = {v0, v1, v2, v3};
    const Eigen::Vector3d g0 = -(G.col(0) + G.col(1) + G.col(2));
    for (int k = 0; k < 4; ++k) {
      const int i = p.var[vs[k]];
      if (i < 0) continue;
      const Eigen::Vector3d gk = k == 0 ? g0 : Eigen::Vector3d(G.col(k - 1));
      (*g)(i) += gk(0);
      (*g)(i + 1) += gk(1);
      (*g)(i + 2) += gk(2);
    }
  }
  return out;
}

// Threads for the energy evaluation: split the active tets in chunks for large problems.
int num_threads(size_t active) {
  if (active < 8000) return 1;
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  return static_cast<int>(std::min<unsigned>(hw, 8));
}

}  // namespace

UntangleEval evaluate(const UntangleProblem& p, const Points& x, double eps, Eigen::VectorXd* g) {
  if (p.device) return p.device->run(x, eps, g);
  const size_t m = p.active.size();
  const int nt = num_threads(m);
  if (nt == 1) return evaluate_range(p, x, eps, g, 0, m);
  std::vector<UntangleEval> part(nt);
  std::vector<Eigen::VectorXd> gl(nt);
  std::vector<std::thread> pool;
  for (int k = 1; k < nt; ++k) {
    if (g) gl[k].resize(g->size());
    pool.emplace_back([&, k] { part[k] = evaluate_range(p, x, eps, g ? &gl[k] : nullptr, m * k / nt, m * (k + 1) / nt); });
  }
  part[0] = evaluate_range(p, x, eps, g, 0, m / nt);
  for (auto& th : pool) th.join();
  UntangleEval out = part[0];
  for (int k = 1; k < nt; ++k) {
    out.energy += part[k].energy;
    out.min_det = std::min(out.min_det, part[k].min_det);
    out.nonpositive += part[k].nonpositive;
    if (g) *g += gl[k];
  }
  return out;
}

}  // namespace vpm
