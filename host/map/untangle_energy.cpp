// Host evaluation of the untangling energy and gradient (see map/untangle_problem.hpp).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.hpp"
#include "core/worker_pool.hpp"
#include "map/untangle_problem.hpp"

namespace vpm {

namespace detail {
// a tet's energy and the factors of its gradient, shared with kernels/untangle.cl
#include "kernels/untangle_energy.clh"
}  // namespace detail

namespace {

// Below this many active tets a thread's share costs less than waking it (measured on the
// volume map's local problems: bench/results/LEDGER.md).
constexpr size_t kMinTetsPerThread = 512;

int threads_for(size_t active, int max_threads) {
  return static_cast<int>(std::clamp<size_t>(active / kMinTetsPerThread, 1, static_cast<size_t>(max_threads)));
}

}  // namespace

struct UntangleHostEval::State {
  const UntangleProblem& p;
  std::vector<int> start, corner;  // free vertex j: its corners 4 a + k, a ascending (CSR)
  std::vector<double> fw;          // per active tet: weight * energy
  std::vector<double> dedx;        // per active tet: dE/dX, 3 x 3 column-major (column k: corner k + 1)
  std::vector<double> part_min;    // per thread: smallest det J of its tets
  std::vector<int> part_nonpositive;
  detail::WorkerPool pool;

  State(const UntangleProblem& problem, int threads) : p(problem), pool(threads) {
    const Tets& t = *p.tets;
    const size_t m = p.active.size(), nf = p.free_vertices.size();
    start.assign(nf + 1, 0);
    for (size_t a = 0; a < m; ++a)
      for (int k = 0; k < 4; ++k)
        if (const int i = p.var[t(p.active[a], k)]; i >= 0) ++start[i / 3 + 1];
    for (size_t j = 0; j < nf; ++j) start[j + 1] += start[j];
    corner.resize(start[nf]);
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (size_t a = 0; a < m; ++a)
      for (int k = 0; k < 4; ++k)
        if (const int i = p.var[t(p.active[a], k)]; i >= 0) corner[fill[i / 3]++] = static_cast<int>(4 * a + k);
    fw.resize(m);
    part_min.resize(pool.threads());
    part_nonpositive.resize(pool.threads());
  }

  // Energies and (with_gradient) dE/dX of active tets [begin, end); their smallest det J and
  // count of det J <= 0 in this part's slot.
  void tets(const Points& x, double eps, bool with_gradient, size_t begin, size_t end, int part) {
    const Tets& t = *p.tets;
    const double th = p.theta;
    double min_det = std::numeric_limits<double>::infinity();
    int nonpositive = 0;
    for (size_t a = begin; a < end; ++a) {
      const int ti = p.active[a];
      const int v0 = t(ti, 0);
      Eigen::Matrix3d X;
      X.col(0) = (x.row(t(ti, 1)) - x.row(v0)).transpose();
      X.col(1) = (x.row(t(ti, 2)) - x.row(v0)).transpose();
      X.col(2) = (x.row(t(ti, 3)) - x.row(v0)).transpose();
      const Eigen::Matrix3d J = X * p.rinv[a];
      Eigen::Matrix3d C;  // cofactor matrix: d det / d J
      C.col(0) = J.col(1).cross(J.col(2));
      C.col(1) = J.col(2).cross(J.col(0));
      C.col(2) = J.col(0).cross(J.col(1));
      const double d = J.col(0).dot(C.col(0));
      min_det = std::min(min_det, d);
      if (d <= 0) ++nonpositive;
      double k1, k2;
      const double f = detail::ue_energy(d, J.squaredNorm(), eps, th, &k1, &k2);
      const double w = p.weight[a];
      fw[a] = w * f;
      if (!with_gradient) continue;
      const Eigen::Matrix3d G = (w * (k1 * J + k2 * C)) * p.rinv[a].transpose();  // dE/dX
      Eigen::Map<Eigen::Matrix3d>(dedx.data() + 9 * a) = G;
    }
    part_min[part] = min_det;
    part_nonpositive[part] = nonpositive;
  }

  // The gradient of free vertices [begin, end): each corner's dE/dX summed in tet order (corner
  // 0's is minus the sum of the three columns).
  void gather(Eigen::VectorXd& g, size_t begin, size_t end) const {
    for (size_t j = begin; j < end; ++j) {
      double s[3] = {0, 0, 0};
      for (int c = start[j]; c < start[j + 1]; ++c) {
        const double* G = dedx.data() + 9 * static_cast<size_t>(corner[c] / 4);
        const int k = corner[c] % 4;
        for (int r = 0; r < 3; ++r) s[r] += k == 0 ? -((G[r] + G[3 + r]) + G[6 + r]) : G[3 * (k - 1) + r];
      }
      for (int r = 0; r < 3; ++r) g(static_cast<Eigen::Index>(3 * j) + r) = s[r];
    }
  }
};

UntangleHostEval::UntangleHostEval(const UntangleProblem& p, int threads)
    : s_(std::make_unique<State>(p, threads > 0 ? threads : threads_for(p.active.size(), detail::host_threads()))) {}

UntangleHostEval::~UntangleHostEval() = default;

UntangleEval UntangleHostEval::run(const Points& x, double eps, Eigen::VectorXd* g) {
  State& s = *s_;
  const size_t m = s.p.active.size(), nf = s.p.free_vertices.size();
  const int T = s.pool.threads();
  if (g && s.dedx.empty()) s.dedx.resize(9 * m);
  s.pool.run([&](int k) { s.tets(x, eps, g != nullptr, m * k / T, m * (k + 1) / T, k); });
  if (g) s.pool.run([&](int k) { s.gather(*g, nf * k / T, nf * (k + 1) / T); });
  UntangleEval out;
  out.min_det = std::numeric_limits<double>::infinity();
  for (int k = 0; k < T; ++k) {
    out.min_det = std::min(out.min_det, s.part_min[k]);
    out.nonpositive += s.part_nonpositive[k];
  }
  for (size_t a = 0; a < m; ++a) out.energy += s.fw[a];  // in tet order, whatever T
  return out;
}

UntangleEval evaluate(const UntangleProblem& p, const Points& x, double eps, Eigen::VectorXd* g) {
  if (p.device) return p.device->run(x, eps, g);
  if (p.host) return p.host->run(x, eps, g);
  return UntangleHostEval(p).run(x, eps, g);
}

}  // namespace vpm
