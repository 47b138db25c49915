// The numerical steps of the sphere map (map/sphere_steps.hpp).
#include "map/sphere_steps.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <utility>
#include <Eigen/IterativeLinearSolvers>
#include <complex>

#include "linalg/sparse_cholesky.hpp"
#include "vpm/error.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/topology.hpp"

namespace vpm::detail {

using Trip = Eigen::Triplet<double>;

// Cotangent weights w_ij = (cot a + cot b)/2 of a triangle surface, as a Laplacian L
// (L_ii = sum_j w_ij, L_ij = -w_ij). `clamp` > 0 replaces weights below clamp * mean by that.
SpMat cot_laplacian(const Points& p, const Triangles& f, double clamp) {
  const int k = static_cast<int>(p.rows());
  std::map<std::pair<int, int>, double> w;
  for (Eigen::Index i = 0; i < f.rows(); ++i)
    for (int c = 0; c < 3; ++c) {
      const int o = f(i, c), a = f(i, (c + 1) % 3), b = f(i, (c + 2) % 3);
      const Eigen::Vector3d u = p.row(a) - p.row(o), v = p.row(b) - p.row(o);
      const double cr = std::max(u.cross(v).norm(), 1e-300);
      w[{std::min(a, b), std::max(a, b)}] += 0.5 * u.dot(v) / cr;
    }
  if (clamp > 0) {
    double mean = 0;
    for (auto& [e, x] : w) mean += std::abs(x);
    mean /= std::max<size_t>(w.size(), 1);
    for (auto& [e, x] : w) x = std::max(x, clamp * mean);
  }
  std::vector<Trip> t;
  t.reserve(4 * w.size());
  for (const auto& [e, x] : w) {
    t.emplace_back(e.first, e.second, -x);
    t.emplace_back(e.second, e.first, -x);
    t.emplace_back(e.first, e.first, x);
    t.emplace_back(e.second, e.second, x);
  }
  SpMat L(k, k);
  L.setFromTriplets(t.begin(), t.end());
  return L;
}

// Solves A_FF u_F = -A_FB u_B for the columns of u (k x c), rows with fixed[i] given, by a
// sparse Cholesky factorisation (iterative = false) or Jacobi-preconditioned CG to relative
// residual `tol` (iterative = true; warm start from the free rows of u).
// Returns false if the solve failed or the result is not finite.
FreeRows free_rows(const SpMat& A, const std::vector<char>& fixed, const Eigen::MatrixXd& u,
                   const Eigen::MatrixXd* source) {
  const int k = static_cast<int>(A.rows());
  FreeRows r;
  r.idx.assign(static_cast<size_t>(k), -1);
  int nf = 0;
  for (int i = 0; i < k; ++i)
    if (!fixed[i]) r.idx[i] = nf++;
  std::vector<Trip> tf;
  r.rhs = Eigen::MatrixXd::Zero(nf, u.cols());
  if (source)
    for (int i = 0; i < k; ++i)
      if (r.idx[i] >= 0) r.rhs.row(r.idx[i]) = source->row(i);
  for (int j = 0; j < A.outerSize(); ++j)
    for (SpMat::InnerIterator it(A, j); it; ++it) {
      const int i = static_cast<int>(it.row());
      if (r.idx[i] < 0) continue;
      if (r.idx[j] >= 0) tf.emplace_back(r.idx[i], r.idx[j], it.value());
      else r.rhs.row(r.idx[i]) -= it.value() * u.row(j);
    }
  r.a.resize(nf, nf);
  r.a.setFromTriplets(tf.begin(), tf.end());
  return r;
}

bool dirichlet_solve(const SpMat& A, const std::vector<char>& fixed, Eigen::MatrixXd& u, bool iterative,
                     double tol, int* iterations) {
  const int k = static_cast<int>(A.rows());
  FreeRows fr = free_rows(A, fixed, u);
  const std::vector<int>& idx = fr.idx;
  const int nf = static_cast<int>(fr.a.rows());
  if (nf == 0) return true;
  const SpMat& Aff = fr.a;
  const Eigen::MatrixXd& rhs = fr.rhs;
  if (iterative) {
    Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper> cg(Aff);
    cg.setTolerance(tol);
    cg.setMaxIterations(std::max(1000, 10 * nf));
    int its = 0;
    for (Eigen::Index c = 0; c < u.cols(); ++c) {
      Eigen::VectorXd x0(nf);
      for (int i = 0; i < k; ++i)
        if (idx[i] >= 0) x0(idx[i]) = u(i, c);
      const Eigen::VectorXd sol = cg.solveWithGuess(rhs.col(c), x0);
      its += static_cast<int>(cg.iterations());
      if (cg.info() != Eigen::Success || !sol.allFinite()) return false;
      for (int i = 0; i < k; ++i)
        if (idx[i] >= 0) u(i, c) = sol(idx[i]);
    }
    if (iterations) *iterations = its;
    return true;
  }
  SparseCholesky chol;
  if (!chol.factorize(Aff)) return false;
  const Eigen::MatrixXd sol = chol.solve(rhs);
  if (!sol.allFinite()) return false;
  for (int i = 0; i < k; ++i)
    if (idx[i] >= 0) u.row(i) = sol.row(idx[i]);
  return true;
}

Points inverse_stereo_north(const Eigen::MatrixXd& z) {  // plane origin -> south pole
  Points s(z.rows(), 3);
  for (Eigen::Index i = 0; i < z.rows(); ++i) {
    const double r2 = z(i, 0) * z(i, 0) + z(i, 1) * z(i, 1);
    s.row(i) << 2 * z(i, 0) / (1 + r2), 2 * z(i, 1) / (1 + r2), (r2 - 1) / (1 + r2);
  }
  return s;
}

// Möbius automorphism of the ball taking a to 0, applied to a point x of the sphere.
namespace {

Eigen::Vector3d moebius(const Eigen::Vector3d& x, const Eigen::Vector3d& a) {
  const Eigen::Vector3d d = x - a;
  const double a2 = a.squaredNorm();
  const double den = 1 - 2 * a.dot(x) + a2 * x.squaredNorm();
  return ((1 - a2) * d - d.squaredNorm() * a) / den;
}

}  // namespace

void normalize_rows(Points& s) {
  for (Eigen::Index i = 0; i < s.rows(); ++i) {
    const double r = s.row(i).norm();
    if (r > 0) s.row(i) /= r;
  }
}

// South-pole correction: compose with the quasi-conformal map whose Beltrami coefficient
// cancels the distortion near the north pole (linear Beltrami solver).
bool south_pole_correction(const Points& in, const Triangles& f, Points& s) {
  const int k = static_cast<int>(s.rows());
  std::vector<int> order(k);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return s(a, 2) < s(b, 2); });
  const int nfix = std::min(k, std::max(k / 10, 3));
  std::vector<char> fixed(k, 0);
  for (int i = 0; i < nfix; ++i) fixed[order[i]] = 1;
  Eigen::MatrixXd P(k, 2);
  for (int i = 0; i < k; ++i) {
    const double d = std::max(1 + s(i, 2), 1e-14);
    P.row(i) << s(i, 0) / d, s(i, 1) / d;
  }
  std::vector<Trip> t;
  t.reserve(9 * f.rows());
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    const int v[3] = {f(i, 0), f(i, 1), f(i, 2)};
    const Eigen::Vector2d p0 = P.row(v[0]), p1 = P.row(v[1]), p2 = P.row(v[2]);
    const double area2 = (p1 - p0).x() * (p2 - p0).y() - (p1 - p0).y() * (p2 - p0).x();
    if (!(std::abs(area2) > 0) || !std::isfinite(area2)) continue;
    // gradients of the hat functions on the planar triangle
    Eigen::Vector2d g[3];
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector2d e = P.row(v[(c + 2) % 3]) - P.row(v[(c + 1) % 3]);
      g[c] = Eigen::Vector2d(-e.y(), e.x()) / area2;
    }
    Eigen::Vector3d fu = Eigen::Vector3d::Zero(), fv = Eigen::Vector3d::Zero();
    for (int c = 0; c < 3; ++c) {
      fu += g[c].x() * in.row(v[c]).transpose();
      fv += g[c].y() * in.row(v[c]).transpose();
    }
    const double E = fu.squaredNorm(), G = fv.squaredNorm(), F = fu.dot(fv);
    std::complex<double> mu(E - G, 2 * F);
    mu /= E + G + 2 * std::sqrt(std::max(E * G - F * F, 0.0));
    if (std::abs(mu) > 0.99) mu *= 0.99 / std::abs(mu);
    const double rho = mu.real(), tau = mu.imag(), den = 1 - std::norm(mu);
    Eigen::Matrix2d A;
    A << ((1 - rho) * (1 - rho) + tau * tau) / den, -2 * tau / den, -2 * tau / den,
        ((1 + rho) * (1 + rho) + tau * tau) / den;
    const double area = 0.5 * std::abs(area2);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) t.emplace_back(v[a], v[b], area * g[a].dot(A * g[b]));
  }
  SpMat K(k, k);
  K.setFromTriplets(t.begin(), t.end());
  Eigen::MatrixXd u = P;
  if (!dirichlet_solve(K, fixed, u)) return false;
  for (int i = 0; i < k; ++i) {
    const double r2 = u.row(i).squaredNorm();
    s.row(i) << 2 * u(i, 0) / (1 + r2), 2 * u(i, 1) / (1 + r2), (1 - r2) / (1 + r2);
  }
  return s.allFinite();
}

// Moves the area-weighted centroid of the sphere points to the origin. Returns iterations.
int moebius_balance(const Eigen::VectorXd& w, Points& s, int max_it, double tol, double* final_norm) {
  const double ws = w.sum();
  auto centroid = [&](const Points& q) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (Eigen::Index i = 0; i < q.rows(); ++i) c += w(i) * q.row(i).transpose();
    return Eigen::Vector3d(c / ws);
  };
  Eigen::Vector3d c = centroid(s);
  int it = 0;
  for (; it < max_it && c.norm() > tol; ++it) {
    double step = 1.0;
    bool ok = false;
    for (int ls = 0; ls < 30; ++ls) {
      Points q(s.rows(), 3);
      const Eigen::Vector3d a = step * c;
      for (Eigen::Index i = 0; i < s.rows(); ++i) q.row(i) = moebius(s.row(i).transpose(), a).transpose();
      normalize_rows(q);
      const Eigen::Vector3d cn = centroid(q);
      if (q.allFinite() && cn.norm() < c.norm()) {
        s = std::move(q);
        c = cn;
        ok = true;
        break;
      }
      step *= 0.5;
    }
    if (!ok) break;
  }
  if (final_norm) *final_norm = c.norm();
  return it;
}

// Area-equalising flow on the sphere (density-equalising: vertices move down the gradient
// of the area density rho = (input area share) / (sphere area share), diffused implicitly).
// A step is halved until it flips no new triangle and either unflips one or lowers the area
// distortion (so it also repairs chord triangles flipped by extreme conformal scale factors).
// Stops early once no flip is left and the distortion changes by less than 1e-4 (when
// `until_unflipped`, as soon as no flip is left). Returns steps taken.
int area_flow(const Points& in, const Triangles& f, Points& s, int steps, bool until_unflipped) {
  const int k = static_cast<int>(s.rows());
  Eigen::VectorXd ain(f.rows());
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    const Eigen::Vector3d p0 = in.row(f(i, 0)), p1 = in.row(f(i, 1)), p2 = in.row(f(i, 2));
    ain(i) = 0.5 * (p1 - p0).cross(p2 - p0).norm();
  }
  ain /= ain.sum();
  int done = 0;
  for (int st = 0; st < steps; ++st) {
    Eigen::VectorXd asp(f.rows());
    for (Eigen::Index i = 0; i < f.rows(); ++i) {
      const Eigen::Vector3d p0 = s.row(f(i, 0)), p1 = s.row(f(i, 1)), p2 = s.row(f(i, 2));
      asp(i) = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    }
    asp /= asp.sum();
    // vertex density: ratio of input to sphere area around the vertex
    Eigen::VectorXd vin = Eigen::VectorXd::Zero(k), vsp = Eigen::VectorXd::Zero(k);
    for (Eigen::Index i = 0; i < f.rows(); ++i)
      for (int c = 0; c < 3; ++c) {
        vin(f(i, c)) += ain(i);
        vsp(f(i, c)) += asp(i);
      }
    Eigen::VectorXd rho = vin.cwiseQuotient(vsp.cwiseMax(1e-300));
    // per-face gradient of rho on the sphere's chord triangles, averaged to vertices
    Points grad = Points::Zero(k, 3);
    for (Eigen::Index i = 0; i < f.rows(); ++i) {
      const int v[3] = {f(i, 0), f(i, 1), f(i, 2)};
      const Eigen::Vector3d p0 = s.row(v[0]), p1 = s.row(v[1]), p2 = s.row(v[2]);
      Eigen::Vector3d nrm = (p1 - p0).cross(p2 - p0);
      const double a2 = nrm.norm();
      if (!(a2 > 0)) continue;
      nrm /= a2;
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      for (int c = 0; c < 3; ++c) {
        const Eigen::Vector3d e = s.row(v[(c + 2) % 3]) - s.row(v[(c + 1) % 3]);
        g += rho(v[c]) * nrm.cross(e) / a2;
      }
      for (int c = 0; c < 3; ++c) grad.row(v[c]) += asp(i) * g.transpose();
    }
    for (int i = 0; i < k; ++i) {
      grad.row(i) /= std::max(vsp(i), 1e-300);
      grad.row(i) /= std::max(rho(i), 1e-300);
      const Eigen::Vector3d x = s.row(i);
      grad.row(i) -= grad.row(i).dot(x) * x.transpose();  // tangential
    }
    // step so that no vertex moves more than a fifth of the mean edge length; halved until
    // no triangle flips and the area distortion decreases
    double gmax = 0;
    for (int i = 0; i < k; ++i) gmax = std::max(gmax, grad.row(i).norm());
    if (!(gmax > 0)) break;
    const double h = std::sqrt(4 * M_PI / k);  // mean edge length on the sphere
    double dt = 0.2 * h / gmax;
    bool ok = false;
    const double before = area_distortion(in, s, f);
    const int flips_before = flipped_sphere_triangles(s, f);
    for (int ls = 0; ls < 8; ++ls) {
      Points q = s - dt * grad;  // down the density gradient: expand where rho is high
      normalize_rows(q);
      const int fq = flipped_sphere_triangles(q, f);
      if (fq < flips_before || (fq == flips_before && area_distortion(in, q, f) < before)) {
        s = std::move(q);
        ok = true;
        break;
      }
      dt *= 0.5;
    }
    if (!ok) break;
    ++done;
    if (until_unflipped && flipped_sphere_triangles(s, f) == 0) break;
  }
  return done;
}


}  // namespace vpm::detail
