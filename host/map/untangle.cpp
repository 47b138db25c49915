// Garanzha et al. 2021 untangler: per-tet energy, L-BFGS, eps schedule (see vpm/untangle.hpp).
#include "vpm/untangle.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <memory>
#include <limits>
#include <string>
#include <thread>

#include <boost/compute/container/vector.hpp>

#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace {

// chi(D, eps) = (D + sqrt(eps^2 + D^2)) / 2, evaluated without cancellation for D < 0.
inline double chi(double d, double eps) {
  const double s = std::sqrt(eps * eps + d * d);
  return d >= 0 ? 0.5 * (d + s) : 0.5 * eps * eps / (s - d);
}

// The optimisation problem: active tets (with inverse reference edge matrices and weights),
// free vertices (their coordinates are the unknowns z, 3 per free vertex).
struct Problem {
  const Tets* tets = nullptr;
  std::vector<int> active;               // tet indices
  std::vector<Eigen::Matrix3d> rinv;     // R^-1 per active tet (R scaled reference edges)
  std::vector<double> weight;            // normalised reference volume per active tet
  std::vector<int> var;                  // per vertex: index of its first unknown, or -1
  std::vector<int> free_vertices;
  double theta = 1.0 / 128.0;
  struct DeviceEval* device = nullptr;  // OpenCL evaluation when set
};

struct Eval {
  double energy = 0;
  double min_det = 0;
  int nonpositive = 0;
};

// Energy (and gradient if g != nullptr, zeroed first) over active tets [begin, end).
Eval evaluate_range(const Problem& p, const Points& x, double eps, Eigen::VectorXd* g, size_t begin,
                    size_t end) {
  Eval out;
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
    const double s = std::sqrt(eps * eps + d * d);
    const double c = d >= 0 ? 0.5 * (d + s) : 0.5 * eps * eps / (s - d);
    const double dc = c / s;  // chi'(D)
    const double tr = J.squaredNorm();
    const double c23 = std::cbrt(c * c);  // chi^(2/3)
    const double f = (1 - th) * tr / c23 + th * (d * d + 1) / c;
    const double w = p.weight[a];
    out.energy += w * f;
    if (!g) continue;
    // df/dJ = (1-th) [2 J / c^(2/3) - 2/3 tr c^(-5/3) chi' C] + th [2D/c - (D^2+1) chi'/c^2] C
    const double k1 = (1 - th) * 2.0 / c23;
    const double k2 = -(1 - th) * (2.0 / 3.0) * tr / (c23 * c) * dc + th * (2 * d / c - (d * d + 1) * dc / (c * c));
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

namespace bc = boost::compute;

// OpenCL evaluation: kernels/untangle.cl computes per-tet energies, determinants and corner
// gradients, then gathers the gradient per free vertex; the host sums the energies (fixed
// order) and reads everything back with one synchronisation per evaluation.
struct DeviceEval {
  Device& dev;
  int n = 0, m = 0, nfree = 0;
  bc::vector<int> tv, off, slot;
  bc::vector<double> rinv, w, x, e, d, gt, g;
  bc::kernel ktet, kgather;
  std::vector<double> he, hd;

  DeviceEval(Device& device, const Problem& p, int num_vertices)
      : dev(device), n(num_vertices), m(static_cast<int>(p.active.size())),
        nfree(static_cast<int>(p.free_vertices.size())), tv(device.context()), off(device.context()),
        slot(device.context()), rinv(device.context()), w(device.context()), x(device.context()),
        e(device.context()), d(device.context()), gt(device.context()), g(device.context()) {
    auto& q = dev.queue();
    const Tets& t = *p.tets;
    std::vector<int> htv(4 * static_cast<size_t>(m));
    std::vector<double> hr(9 * static_cast<size_t>(m));
    std::vector<std::vector<int>> per(nfree);
    for (int a = 0; a < m; ++a) {
      for (int k = 0; k < 4; ++k) {
        const int v = t(p.active[a], k);
        htv[4 * a + k] = v;
        if (p.var[v] >= 0) per[p.var[v] / 3].push_back(12 * a + 3 * k);
      }
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) hr[9 * a + 3 * r + c] = p.rinv[a](r, c);
    }
    std::vector<int> hoff(nfree + 1, 0), hslot;
    for (int f = 0; f < nfree; ++f) {
      hoff[f + 1] = hoff[f] + static_cast<int>(per[f].size());
      hslot.insert(hslot.end(), per[f].begin(), per[f].end());
    }
    if (hslot.empty()) hslot.push_back(0);
    tv.assign(htv.begin(), htv.end(), q);
    rinv.assign(hr.begin(), hr.end(), q);
    w.assign(p.weight.begin(), p.weight.end(), q);
    off.assign(hoff.begin(), hoff.end(), q);
    slot.assign(hslot.begin(), hslot.end(), q);
    x.resize(3 * static_cast<size_t>(n), q);
    e.resize(m, q);
    d.resize(m, q);
    gt.resize(12 * static_cast<size_t>(m), q);
    g.resize(std::max(3 * nfree, 1), q);
    he.resize(m);
    hd.resize(m);
    ktet = dev.kernel("untangle", "untangle_tet");
    kgather = dev.kernel("untangle", "untangle_gather");
  }

  Eval run(const Problem& p, const Points& xs, double eps, Eigen::VectorXd* grad) {
    auto& q = dev.queue();
    q.enqueue_write_buffer(x.get_buffer(), 0, sizeof(double) * 3 * n, xs.data());
    ktet.set_arg(0, m);
    ktet.set_arg(1, eps);
    ktet.set_arg(2, p.theta);
    ktet.set_arg(3, grad ? 1 : 0);
    ktet.set_arg(4, tv);
    ktet.set_arg(5, rinv);
    ktet.set_arg(6, w);
    ktet.set_arg(7, x);
    ktet.set_arg(8, e);
    ktet.set_arg(9, d);
    ktet.set_arg(10, gt);
    dev.launch(ktet, m);
    if (grad && nfree > 0) {
      kgather.set_arg(0, nfree);
      kgather.set_arg(1, off);
      kgather.set_arg(2, slot);
      kgather.set_arg(3, gt);
      kgather.set_arg(4, g);
      dev.launch(kgather, nfree);
      q.enqueue_read_buffer_async(g.get_buffer(), 0, sizeof(double) * 3 * nfree, grad->data());
    }
    q.enqueue_read_buffer_async(e.get_buffer(), 0, sizeof(double) * m, he.data());
    q.enqueue_read_buffer_async(d.get_buffer(), 0, sizeof(double) * m, hd.data());
    q.finish();
    Eval out;
    out.min_det = std::numeric_limits<double>::infinity();
    for (int a = 0; a < m; ++a) {
      out.energy += he[a];
      out.min_det = std::min(out.min_det, hd[a]);
      if (hd[a] <= 0) ++out.nonpositive;
    }
    return out;
  }
};

Eval evaluate(const Problem& p, const Points& x, double eps, Eigen::VectorXd* g) {
  if (p.device) return p.device->run(p, x, eps, g);
  const size_t m = p.active.size();
  const int nt = num_threads(m);
  if (nt == 1) return evaluate_range(p, x, eps, g, 0, m);
  std::vector<Eval> part(nt);
  std::vector<Eigen::VectorXd> gl(nt);
  std::vector<std::thread> pool;
  for (int k = 1; k < nt; ++k) {
    if (g) gl[k].resize(g->size());
    pool.emplace_back([&, k] { part[k] = evaluate_range(p, x, eps, g ? &gl[k] : nullptr, m * k / nt, m * (k + 1) / nt); });
  }
  part[0] = evaluate_range(p, x, eps, g, 0, m / nt);
  for (auto& th : pool) th.join();
  Eval out = part[0];
  for (int k = 1; k < nt; ++k) {
    out.energy += part[k].energy;
    out.min_det = std::min(out.min_det, part[k].min_det);
    out.nonpositive += part[k].nonpositive;
    if (g) *g += gl[k];
  }
  return out;
}

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

// L-BFGS with backtracking (Armijo) line search at fixed eps. Returns iterations run.
int lbfgs(const Problem& p, Points& x, double eps, const UntangleOptions& o, int* evals,
          std::chrono::steady_clock::time_point deadline) {
  const int nz = static_cast<int>(3 * p.free_vertices.size());
  if (nz == 0) return 0;
  Eigen::VectorXd z = gather(p, x), g(nz), gn(nz);
  double e = evaluate(p, x, eps, &g).energy;
  ++*evals;
  const double g0 = g.lpNorm<Eigen::Infinity>();
  std::deque<Eigen::VectorXd> S, Y;
  std::deque<double> rho;
  int it = 0;
  for (; it < o.max_lbfgs_iterations; ++it) {
    if (g.lpNorm<Eigen::Infinity>() <= o.gradient_tolerance * (1 + g0)) break;
    if (o.max_seconds > 0 && std::chrono::steady_clock::now() > deadline) break;
    // two-loop recursion
    Eigen::VectorXd q = -g;
    std::vector<double> alpha(S.size());
    for (int k = static_cast<int>(S.size()) - 1; k >= 0; --k) {
      alpha[k] = rho[k] * S[k].dot(q);
      q -= alpha[k] * Y[k];
    }
    if (!S.empty()) {
      q *= S.back().dot(Y.back()) / Y.back().squaredNorm();
    } else {
      // first step: move the fastest vertex by a small fraction of the mesh scale
      const double gi = g.lpNorm<Eigen::Infinity>();
      double scale = 0;
      for (int k = 0; k < nz; ++k) scale = std::max(scale, std::abs(z(k)));
      q *= (gi > 0 ? 1e-3 * std::max(scale, 1e-12) / gi : 0.0);
    }
    for (size_t k = 0; k < S.size(); ++k) {
      const double b = rho[k] * Y[k].dot(q);
      q += (alpha[k] - b) * S[k];
    }
    double slope = g.dot(q);
    if (!(slope < 0)) {  // not a descent direction: restart with steepest descent
      S.clear();
      Y.clear();
      rho.clear();
      q = -g * (1e-3 / std::max(g.lpNorm<Eigen::Infinity>(), 1e-300));
      slope = g.dot(q);
      if (!(slope < 0)) break;
    }
    double step = 1.0, en = 0;
    bool ok = false;
    const Eigen::VectorXd z0 = z;
    for (int ls = 0; ls < 40; ++ls) {
      z = z0 + step * q;
      scatter(p, z, x);
      en = evaluate(p, x, eps, &gn).energy;
      ++*evals;
      if (std::isfinite(en) && en <= e + 1e-4 * step * slope) {
        ok = true;
        break;
      }
      step *= 0.5;
    }
    if (!ok) {
      z = z0;
      scatter(p, z, x);
      if (S.empty()) break;  // even a steepest-descent step fails: converged to precision
      S.clear();
      Y.clear();
      rho.clear();
      continue;
    }
    Eigen::VectorXd s = z - z0, y = gn - g;
    const double sy = s.dot(y);
    if (sy > 1e-300) {
      S.push_back(std::move(s));
      Y.push_back(std::move(y));
      rho.push_back(1.0 / sy);
      if (static_cast<int>(S.size()) > o.lbfgs_memory) {
        S.pop_front();
        Y.pop_front();
        rho.pop_front();
      }
    }
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

UntangleResult run(Problem& p, const Points& reference, const Tets& tets, Points& x,
                   const UntangleOptions& o, Device* device) {
  const auto t0 = std::chrono::steady_clock::now();
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
  // Reference edge matrices, weights, scale.
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

  std::unique_ptr<DeviceEval> dev_eval;
  if (device && !device->is_host()) {
    dev_eval = std::make_unique<DeviceEval>(*device, p, static_cast<int>(x.rows()));
    p.device = dev_eval.get();
  }
  Eval ev = evaluate(p, x, 1.0, nullptr);
  r.min_det_before = ev.min_det;
  double eps = std::sqrt(1e-12 + 0.04 * std::pow(std::min(ev.min_det, 0.0), 2));
  double e_prev = evaluate(p, x, eps, nullptr).energy;
  r.energy_before = e_prev;
  int evals = 0;
  const auto deadline = t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                  std::chrono::duration<double>(std::max(o.max_seconds, 0.0)));
  for (int outer = 0; outer < o.max_outer_iterations; ++outer) {
    if (o.max_seconds > 0 && std::chrono::steady_clock::now() > deadline) {
      r.out_of_time = true;
      break;
    }
    r.lbfgs_iterations += lbfgs(p, x, eps, o, &evals, deadline);
    ++r.iterations;
    ev = evaluate(p, x, eps, nullptr);
    const double e = ev.energy;
    r.energy_after = e;
    r.final_eps = eps;
    const double sigma = std::max(1.0 - e / e_prev, 0.1);
    const double mu = (1 - sigma) * chi(ev.min_det, eps);
    if (ev.min_det < mu)
      eps = 2 * std::sqrt(mu * (mu - ev.min_det));
    else
      eps = 1e-10;
    if (ev.min_det > 0 &&
        (o.stop_when_untangled || std::abs(e_prev - e) <= o.outer_energy_tolerance * std::abs(e)))
      break;
    e_prev = e;
  }
  r.min_det_after = evaluate(p, x, 1.0, nullptr).min_det;
  p.device = nullptr;
  r.evaluations = evals;
  r.inverted_tets = inverted_tets(x, tets);
  r.inverted_after = static_cast<int>(r.inverted_tets.size());
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
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

UntangleResult untangle(Device& device, const Points& reference, const Tets& tets, Points& x,
                        const std::vector<char>& fixed, const UntangleOptions& options) {
  check_sizes(reference, tets, x, fixed);
  Problem p;
  const int n = static_cast<int>(x.rows());
  p.var.assign(n, -1);
  // only vertices used by some tet are unknowns
  std::vector<char> used(n, 0);
  for (Eigen::Index i = 0; i < tets.rows(); ++i)
    for (int c = 0; c < 4; ++c) used[tets(i, c)] = 1;
  for (int v = 0; v < n; ++v)
    if (!fixed[v] && used[v]) {
      p.var[v] = static_cast<int>(3 * p.free_vertices.size());
      p.free_vertices.push_back(v);
    }
  for (Eigen::Index i = 0; i < tets.rows(); ++i) {
    bool any = false;
    for (int c = 0; c < 4; ++c) any = any || p.var[tets(i, c)] >= 0;
    if (any) p.active.push_back(static_cast<int>(i));
  }
  return run(p, reference, tets, x, options, &device);
}

UntangleResult untangle_local(Device& device, const Points& reference, const Tets& tets, Points& x,
                              const std::vector<char>& fixed, const std::vector<int>& folded,
                              int rings, const UntangleOptions& options) {
  check_sizes(reference, tets, x, fixed);
  const int n = static_cast<int>(x.rows());
  Problem p;
  p.var.assign(n, -1);
  std::vector<char> in(n, 0);
  std::vector<int> layer;
  for (int t : folded) {
    if (t < 0 || t >= tets.rows())
      throw InputError("untangle_local: folded tet index " + std::to_string(t) + " out of range");
    for (int c = 0; c < 4; ++c)
      if (!in[tets(t, c)]) {
        in[tets(t, c)] = 1;
        layer.push_back(tets(t, c));
      }
  }
  const Incidence inc = vertex_tet_incidence(n, tets);
  for (int r = 0; r < rings; ++r) {
    std::vector<int> next;
    for (int v : layer)
      for (int k = inc.offset[v]; k < inc.offset[v + 1]; ++k) {
        const int t = inc.tet_of[k];
        for (int c = 0; c < 4; ++c)
          if (!in[tets(t, c)]) {
            in[tets(t, c)] = 1;
            next.push_back(tets(t, c));
          }
      }
    layer.swap(next);
  }
  for (int v = 0; v < n; ++v)
    if (in[v] && !fixed[v]) {
      p.var[v] = static_cast<int>(3 * p.free_vertices.size());
      p.free_vertices.push_back(v);
    }
  std::vector<char> act(tets.rows(), 0);
  for (int v : p.free_vertices)
    for (int k = inc.offset[v]; k < inc.offset[v + 1]; ++k) act[inc.tet_of[k]] = 1;
  for (Eigen::Index i = 0; i < tets.rows(); ++i)
    if (act[i]) p.active.push_back(static_cast<int>(i));
  return run(p, reference, tets, x, options, &device);
}

Json UntangleResult::to_json() const {
  Json j = Json::object();
  j["inverted_before"] = inverted_before;
  j["inverted_after"] = inverted_after;
  j["iterations"] = iterations;
  j["lbfgs_iterations"] = lbfgs_iterations;
  j["evaluations"] = evaluations;
  j["free_vertices"] = free_vertices;
  j["active_tets"] = active_tets;
  j["min_det_before"] = min_det_before;
  j["min_det_after"] = min_det_after;
  j["energy_before"] = energy_before;
  j["energy_after"] = energy_after;
  j["final_eps"] = final_eps;
  j["seconds"] = seconds;
  j["out_of_time"] = out_of_time;
  Json list = Json::array();
  for (size_t i = 0; i < inverted_tets.size() && i < 20; ++i) list.push_back(inverted_tets[i]);
  j["inverted_tets_first"] = list;
  return j;
}

}  // namespace vpm
