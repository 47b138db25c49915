// Initial map of a tet mesh to the unit ball (see vpm/initial_map.hpp).
#include "vpm/initial_map.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/metrics.hpp"
#include "vpm/solver.hpp"
#include "vpm/topology.hpp"
#include "vpm/untangle.hpp"
#include "vpm/timing.hpp"
#include "vpm/format.hpp"

namespace vpm {

namespace {


using SpMat = Eigen::SparseMatrix<double>;
using Trip = Eigen::Triplet<double>;


// ------------------------------------------------------------------------------ split

constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

std::set<std::pair<int, int>> surface_edges(const Triangles& f) {
  std::set<std::pair<int, int>> e;
  for (Eigen::Index i = 0; i < f.rows(); ++i)
    for (int k = 0; k < 3; ++k) {
      int a = f(i, k), b = f(i, (k + 1) % 3);
      if (a > b) std::swap(a, b);
      e.insert({a, b});
    }
  return e;
}

}  // namespace

int count_four_boundary_tets(const Tets& tets, const std::vector<char>& boundary) {
  int c = 0;
  for (Eigen::Index i = 0; i < tets.rows(); ++i)
    if (boundary[tets(i, 0)] && boundary[tets(i, 1)] && boundary[tets(i, 2)] && boundary[tets(i, 3)]) ++c;
  return c;
}

SplitResult split_boundary_edges(const TetMesh& input, int max_rounds) {
  SplitResult r;
  const int n0 = input.num_vertices();
  const Triangles bf = boundary_faces(input.tets);
  std::vector<char> bnd = boundary_vertex_mask(n0, bf);
  const auto bedges = surface_edges(bf);
  r.four_boundary_tets_before = count_four_boundary_tets(input.tets, bnd);

  std::vector<Eigen::Vector3d> X(n0);
  for (int i = 0; i < n0; ++i) X[i] = input.vertices.row(i).transpose();
  // sources[v]: vertices whose average v is (1, 2 or 4 of them)
  std::vector<std::vector<int>> sources(n0);
  for (int i = 0; i < n0; ++i) sources[i] = {i};
  std::vector<std::array<int, 4>> T(input.tets.rows());
  for (Eigen::Index i = 0; i < input.tets.rows(); ++i)
    for (int c = 0; c < 4; ++c) T[i][c] = input.tets(i, c);
  r.parent_tet.resize(T.size());
  std::iota(r.parent_tet.begin(), r.parent_tet.end(), 0);

  auto add_vertex = [&](const Eigen::Vector3d& p, std::vector<int> src) {
    X.push_back(p);
    sources.push_back(std::move(src));
    bnd.push_back(0);
    return static_cast<int>(X.size()) - 1;
  };

  for (int round = 0; round < max_rounds; ++round) {
    std::vector<std::pair<int, int>> cand;
    for (const auto& t : T)
      for (const auto& e : kEdges) {
        int a = t[e[0]], b = t[e[1]];
        if (!bnd[a] || !bnd[b]) continue;
        if (a > b) std::swap(a, b);
        if (!bedges.count({a, b})) cand.push_back({a, b});
      }
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    if (cand.empty()) break;
    ++r.rounds;
    std::vector<std::vector<int>> inc(X.size());
    for (size_t i = 0; i < T.size(); ++i)
      for (int c = 0; c < 4; ++c) inc[T[i][c]].push_back(static_cast<int>(i));
    for (const auto& [a, b] : cand) {
      std::vector<int> around;
      for (int t : inc[a])
        if (T[t][0] == b || T[t][1] == b || T[t][2] == b || T[t][3] == b) around.push_back(t);
      if (around.empty()) continue;
      const int m = add_vertex(0.5 * (X[a] + X[b]), {a, b});
      inc.emplace_back();
      for (int t : around) {
        std::array<int, 4> child = T[t];
        for (int c = 0; c < 4; ++c) {
          if (T[t][c] == b) T[t][c] = m;   // (a, m, ...) stays in slot t
          if (child[c] == a) child[c] = m; // (m, b, ...) is new
        }
        const int tn = static_cast<int>(T.size());
        T.push_back(child);
        r.parent_tet.push_back(r.parent_tet[t]);
        auto& ib = inc[b];
        ib.erase(std::find(ib.begin(), ib.end(), t));
        for (int c = 0; c < 4; ++c)
          if (child[c] != m) inc[child[c]].push_back(tn);
        inc[m].push_back(t);
        inc[m].push_back(tn);
      }
    }
  }
  // Tets still with four boundary vertices have only boundary-surface edges: split 1 -> 4.
  const size_t nt = T.size();
  for (size_t t = 0; t < nt; ++t) {
    const auto q = T[t];
    if (!(bnd[q[0]] && bnd[q[1]] && bnd[q[2]] && bnd[q[3]])) continue;
    const int m = add_vertex(0.25 * (X[q[0]] + X[q[1]] + X[q[2]] + X[q[3]]), {q[0], q[1], q[2], q[3]});
    ++r.centroid_splits;
    for (int k = 0; k < 4; ++k) {
      std::array<int, 4> child = q;
      child[k] = m;
      if (k == 0) {
        T[t] = child;
      } else {
        T.push_back(child);
        r.parent_tet.push_back(r.parent_tet[t]);
      }
    }
  }

  const int n = static_cast<int>(X.size());
  r.inserted_vertices = n - n0;
  TetMesh& m = r.mesh;
  m.vertices.resize(n, 3);
  for (int i = 0; i < n; ++i) m.vertices.row(i) = X[i].transpose();
  m.tets.resize(static_cast<Eigen::Index>(T.size()), 4);
  for (size_t i = 0; i < T.size(); ++i)
    for (int c = 0; c < 4; ++c) m.tets(static_cast<Eigen::Index>(i), c) = T[i][c];
  r.parents.resize(n);
  for (int i = 0; i < n; ++i) {
    if (sources[i].size() == 1) r.parents[i] = {i, i};
    else if (sources[i].size() == 2) r.parents[i] = {sources[i][0], sources[i][1]};
    else r.parents[i] = {-1, -1};
  }
  // Carry fields.
  for (const Field& f : input.point_data) {
    if (f.name == "original_position") continue;
    FieldValues v(n, f.values.cols());
    v.topRows(n0) = f.values;
    for (int i = n0; i < n; ++i) {
      if (f.integer) {
        v.row(i) = v.row(sources[i][0]);
      } else {
        v.row(i).setZero();
        for (int s : sources[i]) v.row(i) += v.row(s);
        v.row(i) /= static_cast<double>(sources[i].size());
      }
    }
    m.set_point_field(f.name, std::move(v), f.integer);
  }
  for (const Field& f : input.cell_data) {
    FieldValues v(m.tets.rows(), f.values.cols());
    for (Eigen::Index i = 0; i < m.tets.rows(); ++i) v.row(i) = f.values.row(r.parent_tet[i]);
    m.set_cell_field(f.name, std::move(v), f.integer);
  }
  m.set_point_field("original_position", FieldValues(m.vertices));
  r.four_boundary_tets_after = count_four_boundary_tets(m.tets, bnd);
  return r;
}

// ------------------------------------------------------------------------ sphere map

double area_distortion(const Points& in, const Points& sp, const Triangles& f) {
  const Eigen::Index k = f.rows();
  if (k == 0) return 0;
  Eigen::VectorXd a(k), b(k);
  for (Eigen::Index i = 0; i < k; ++i) {
    const Eigen::Vector3d p0 = in.row(f(i, 0)), p1 = in.row(f(i, 1)), p2 = in.row(f(i, 2));
    const Eigen::Vector3d q0 = sp.row(f(i, 0)), q1 = sp.row(f(i, 1)), q2 = sp.row(f(i, 2));
    a(i) = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    b(i) = 0.5 * (q1 - q0).cross(q2 - q0).norm();
  }
  const double sa = a.sum(), sb = b.sum();
  double s = 0;
  for (Eigen::Index i = 0; i < k; ++i) s += std::abs((b(i) / sb) / std::max(a(i) / sa, 1e-300) - 1.0);
  return s / static_cast<double>(k);
}

int flipped_sphere_triangles(const Points& sp, const Triangles& f) {
  int c = 0;
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    const Eigen::Vector3d a = sp.row(f(i, 0)), b = sp.row(f(i, 1)), d = sp.row(f(i, 2));
    if (!(a.dot(b.cross(d)) > 0)) ++c;
  }
  return c;
}

namespace {

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
bool dirichlet_solve(const SpMat& A, const std::vector<char>& fixed, Eigen::MatrixXd& u,
                     bool iterative = false, double tol = 1e-10, int* iterations = nullptr) {
  const int k = static_cast<int>(A.rows());
  std::vector<int> idx(k, -1);
  int nf = 0;
  for (int i = 0; i < k; ++i)
    if (!fixed[i]) idx[i] = nf++;
  if (nf == 0) return true;
  std::vector<Trip> tf;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nf, u.cols());
  for (int j = 0; j < A.outerSize(); ++j)
    for (SpMat::InnerIterator it(A, j); it; ++it) {
      const int i = static_cast<int>(it.row());
      if (idx[i] < 0) continue;
      if (idx[j] >= 0) tf.emplace_back(idx[i], idx[j], it.value());
      else rhs.row(idx[i]) -= it.value() * u.row(j);
    }
  SpMat Aff(nf, nf);
  Aff.setFromTriplets(tf.begin(), tf.end());
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
  Eigen::SimplicialLDLT<SpMat> ldlt(Aff);
  if (ldlt.info() != Eigen::Success) return false;
  const Eigen::MatrixXd sol = ldlt.solve(rhs);
  if (ldlt.info() != Eigen::Success || !sol.allFinite()) return false;
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
Eigen::Vector3d moebius(const Eigen::Vector3d& x, const Eigen::Vector3d& a) {
  const Eigen::Vector3d d = x - a;
  const double a2 = a.squaredNorm();
  const double den = 1 - 2 * a.dot(x) + a2 * x.squaredNorm();
  return ((1 - a2) * d - d.squaredNorm() * a) / den;
}

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

}  // namespace

SphereMapResult sphere_map(const TriSurface& surf, const InitialMapOptions& opt) {
  SphereMapResult r;
  Json& rep = r.report;
  rep = Json::object();
  const int nall = static_cast<int>(surf.vertices.rows());
  std::vector<int> loc(nall, -1), used;
  for (Eigen::Index i = 0; i < surf.triangles.rows(); ++i)
    for (int c = 0; c < 3; ++c) {
      const int v = surf.triangles(i, c);
      if (v < 0 || v >= nall) throw InputError("sphere_map: triangle " + std::to_string(i) + " has vertex index out of range");
      if (loc[v] < 0) {
        loc[v] = static_cast<int>(used.size());
        used.push_back(v);
      }
    }
  const int k = static_cast<int>(used.size());
  Triangles f(surf.triangles.rows(), 3);
  for (Eigen::Index i = 0; i < f.rows(); ++i)
    for (int c = 0; c < 3; ++c) f(i, c) = loc[surf.triangles(i, c)];
  Points in(k, 3);
  for (int i = 0; i < k; ++i) in.row(i) = surf.vertices.row(used[i]);
  const SurfaceTopology topo = surface_topology(k, f);
  if (topo.components != 1 || topo.open_edges || topo.nonmanifold_edges || topo.nonmanifold_vertices ||
      topo.euler != 2)
    throw InputError("sphere_map: the boundary is not one closed genus-0 surface (euler " +
                     std::to_string(topo.euler) + ", components " + std::to_string(topo.components) +
                     ", open edges " + std::to_string(topo.open_edges) + ")");
  rep["vertices"] = k;
  rep["faces"] = static_cast<int>(f.rows());

  // 1. most regular triangle
  Eigen::Index big = 0;
  double best = 1e300;
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    const double e1 = (in.row(f(i, 1)) - in.row(f(i, 2))).norm();
    const double e2 = (in.row(f(i, 2)) - in.row(f(i, 0))).norm();
    const double e3 = (in.row(f(i, 0)) - in.row(f(i, 1))).norm();
    const double s = e1 + e2 + e3;
    const double reg = std::abs(e1 / s - 1.0 / 3) + std::abs(e2 / s - 1.0 / 3) + std::abs(e3 / s - 1.0 / 3);
    if (reg < best) {
      best = reg;
      big = i;
    }
  }
  const int p1 = f(big, 0), p2 = f(big, 1), p3 = f(big, 2);
  const Eigen::Vector3d ea = in.row(p2) - in.row(p1), eb = in.row(p3) - in.row(p1);
  const double ratio = 1.0 / ea.norm();
  const double sin1 = ea.cross(eb).norm() / (ea.norm() * eb.norm());
  const double y3 = eb.norm() * sin1 * ratio;
  const double x3 = ea.dot(eb) / ea.norm() * ratio;
  std::vector<char> fixed(k, 0);
  fixed[p1] = fixed[p2] = fixed[p3] = 1;

  Points s;
  int flips = 0;
  const char* weights = "cotangent";
  for (int attempt = 0; attempt < 2; ++attempt) {
    const SpMat L = cot_laplacian(in, f, attempt == 0 ? 0.0 : 1e-3);
    Eigen::MatrixXd z = Eigen::MatrixXd::Zero(k, 2);
    z.row(p1) << 0, 0;
    z.row(p2) << 1, 0;
    z.row(p3) << x3, y3;
    if (!dirichlet_solve(L, fixed, z)) {
      flips = static_cast<int>(f.rows());
      continue;
    }
    const Eigen::RowVector2d mean = z.colwise().mean();
    z.rowwise() -= mean;
    // rescale so the north (big) and south (innermost) triangles have comparable sizes
    s = inverse_stereo_north(z);
    Eigen::Index inner = -1;
    double innermost = 1e300;
    for (Eigen::Index i = 0; i < f.rows(); ++i) {
      if (i == big) continue;
      const double d = z.row(f(i, 0)).norm() + z.row(f(i, 1)).norm() + z.row(f(i, 2)).norm();
      if (d < innermost) {
        innermost = d;
        inner = i;
      }
    }
    auto side = [&](const Eigen::MatrixXd& q, Eigen::Index t) {
      return ((q.row(f(t, 0)) - q.row(f(t, 1))).norm() + (q.row(f(t, 1)) - q.row(f(t, 2))).norm() +
              (q.row(f(t, 2)) - q.row(f(t, 0))).norm()) / 3;
    };
    Eigen::MatrixXd w(k, 2);
    for (int i = 0; i < k; ++i) w.row(i) << s(i, 0) / (1 + s(i, 2)), s(i, 1) / (1 + s(i, 2));
    const double north = side(z, big), south = side(w, inner);
    if (north > 0 && south > 0 && std::isfinite(south)) z *= std::sqrt(north * south) / north;
    s = inverse_stereo_north(z);
    flips = flipped_sphere_triangles(s, f);
    // the big triangle itself is the complement cap: its chord triangle faces inwards unless
    // oriented; count it separately (it is not part of the disk map)
    if (s.allFinite()) {
      // orientation: the disk may be mirrored; test without the big triangle
      Triangles g = f;
      int flips_m = 0;
      Points m = s;
      m.col(0) *= -1;
      flips_m = flipped_sphere_triangles(m, g);
      if (flips_m < flips) {
        s = m;
        flips = flips_m;
      }
      if (flips == 0) break;
    }
    weights = "clamped cotangent";
  }
  rep["planar_weights"] = weights;
  rep["flipped_after_conformal"] = flips;
  r.sphere = s;

  // 2. south-pole correction
  if (opt.south_pole_correction && s.allFinite()) {
    Points c = s;
    if (south_pole_correction(in, f, c)) {
      // orientation may differ: the correction works in the south-pole chart
      Points m = c;
      m.col(0) *= -1;
      int fc = flipped_sphere_triangles(c, f);
      const int fm = flipped_sphere_triangles(m, f);
      if (fm < fc) {
        c = m;
        fc = fm;
      }
      rep["flipped_after_south_pole"] = fc;
      if (fc <= flips) {
        s = c;
        flips = fc;
        rep["south_pole_correction"] = true;
      } else {
        rep["south_pole_correction"] = false;
      }
    } else {
      rep["south_pole_correction"] = false;
    }
  }
  normalize_rows(s);
  // 3. orientation: outward faces must have det > 0 in the majority (total signed volume > 0)
  double vol = 0;
  for (Eigen::Index i = 0; i < f.rows(); ++i)
    vol += Eigen::Vector3d(s.row(f(i, 0))).dot(Eigen::Vector3d(s.row(f(i, 1))).cross(Eigen::Vector3d(s.row(f(i, 2)))));
  rep["mirrored"] = vol < 0;
  if (vol < 0) s.col(0) *= -1;
  rep["area_distortion_conformal"] = area_distortion(in, s, f);

  // 4. Möbius balancing with input vertex areas
  if (opt.moebius_balance) {
    Eigen::VectorXd wv = Eigen::VectorXd::Zero(k);
    for (Eigen::Index i = 0; i < f.rows(); ++i) {
      const Eigen::Vector3d q0 = in.row(f(i, 0)), q1 = in.row(f(i, 1)), q2 = in.row(f(i, 2));
      const double a = 0.5 * (q1 - q0).cross(q2 - q0).norm() / 3;
      for (int c = 0; c < 3; ++c) wv(f(i, c)) += a;
    }
    Points b = s;
    double cn = 0;
    const int its = moebius_balance(wv, b, opt.moebius_max_iterations, opt.moebius_tolerance, &cn);
    const int fb = flipped_sphere_triangles(b, f);
    rep["moebius_iterations"] = its;
    rep["moebius_centroid_norm"] = cn;
    const double before = area_distortion(in, s, f), after = area_distortion(in, b, f);
    rep["area_distortion_balanced"] = after;
    // kept when it flips nothing new and does not raise the area distortion (elongated
    // shapes can be better off unbalanced)
    const bool keep = fb <= flips && after <= before;
    rep["moebius_kept"] = keep;
    if (keep) {
      s = b;
      flips = fb;
    }
  }
  // 5. optional area correction
  if (opt.area_correction) {
    rep["area_correction_steps"] = area_flow(in, f, s, opt.area_correction_steps, false);
  }
  if (flipped_sphere_triangles(s, f) > 0) {
    // Extreme conformal scale factors (protrusions, coarse elongated shapes) can make a chord
    // triangle face inwards: spread the areas until none does.
    rep["flipped_before_repair"] = flipped_sphere_triangles(s, f);
    rep["repair_steps"] = area_flow(in, f, s, std::max(opt.area_correction_steps, 100), true);
  }
  normalize_rows(s);
  flips = flipped_sphere_triangles(s, f);
  rep["area_distortion_final"] = area_distortion(in, s, f);
  rep["flipped_triangles"] = flips;
  r.flipped_triangles = flips;
  r.sphere = Points::Zero(nall, 3);
  r.sphere.col(2).setOnes();
  for (int i = 0; i < k; ++i) r.sphere.row(used[i]) = s.row(i);
  return r;
}

// ----------------------------------------------------------------------- initial map

namespace {

Eigen::Vector3d tet_centroid(const Points& x, const Tets& t, int i) {
  return 0.25 * (x.row(t(i, 0)) + x.row(t(i, 1)) + x.row(t(i, 2)) + x.row(t(i, 3))).transpose();
}

Json vec_json(const Eigen::Vector3d& v) {
  Json a = Json::array();
  for (int c = 0; c < 3; ++c) a.push_back(v(c));
  return a;
}

}  // namespace

InitialMapResult initial_map(Device& device, const TetMesh& input, const InitialMapOptions& opt) {
  const auto t_total = Clock::now();
  InitialMapResult res;
  Json& rep = res.report;
  rep = Json::object();
  rep["device"] = device.name();
  rep["input"]["vertices"] = input.num_vertices();
  rep["input"]["tets"] = input.num_tets();
  if (input.num_tets() == 0) throw InputError("initial_map: the mesh has no tets");
  {
    const Eigen::VectorXd v = tet_volumes(input.vertices, input.tets);
    for (Eigen::Index i = 0; i < v.size(); ++i)
      if (!(v(i) > 0))
        throw InputError("initial_map: input tet " + std::to_string(i) +
                         " is not positively oriented (volume " + format_sig(v(i)) + "); validate the mesh first");
  }

  // input quality
  auto t0 = Clock::now();
  const auto dih = dihedral_angles_deg(input.vertices, input.tets);
  const Eigen::VectorXd tmin = dih.rowwise().minCoeff();
  Eigen::Index worst = 0;
  const double min_dih = tmin.minCoeff(&worst);
  {
    Json& q = rep["input_quality"];
    q["min_dihedral_deg"] = min_dih;
    q["min_dihedral_tet"] = static_cast<int>(worst);
    q["tets_below_1deg"] = static_cast<int>((tmin.array() < 1.0).count());
    q["tets_below_5deg"] = static_cast<int>((tmin.array() < 5.0).count());
    std::vector<int> order(tmin.size());
    std::iota(order.begin(), order.end(), 0);
    const int nw = std::min<int>(opt.report_worst_tets, static_cast<int>(order.size()));
    std::partial_sort(order.begin(), order.begin() + nw, order.end(), [&](int a, int b) { return tmin(a) < tmin(b); });
    Json list = Json::array();
    for (int i = 0; i < nw; ++i) {
      Json w = Json::object();
      w["tet"] = order[i];
      w["min_dihedral_deg"] = tmin(order[i]);
      w["centroid"] = vec_json(tet_centroid(input.vertices, input.tets, order[i]));
      list.push_back(w);
    }
    q["worst"] = list;
    if (min_dih < 1.0)
      q["warning"] = "slivers below 1 degree: meshes with 0.01-0.05 degree slivers defeat the ball map "
                     "(DESIGN.md 4.2); remesh with a dihedral bound";
  }
  auto quality_note = [&]() {
    const Eigen::Vector3d c = tet_centroid(input.vertices, input.tets, static_cast<int>(worst));
    return "input smallest dihedral angle " + format_sig(min_dih) + " deg at tet " + std::to_string(worst) + " (" +
           format_sig(c(0)) + ", " + format_sig(c(1)) + ", " + format_sig(c(2)) + ")";
  };

  const double t_quality = seconds_since(t0);

  // 1. split
  t0 = Clock::now();
  SplitResult sp;
  if (opt.split_edges) {
    sp = split_boundary_edges(input, opt.max_split_rounds);
  } else {
    sp.mesh = input;
    sp.mesh.set_point_field("original_position", FieldValues(input.vertices));
    sp.parent_tet.resize(input.num_tets());
    std::iota(sp.parent_tet.begin(), sp.parent_tet.end(), 0);
  }
  res.mesh = std::move(sp.mesh);
  const TetMesh& m = res.mesh;
  const int n = m.num_vertices();
  {
    Json& s = rep["split"];
    s["rounds"] = sp.rounds;
    s["inserted_vertices"] = sp.inserted_vertices;
    s["four_boundary_tets_before"] = sp.four_boundary_tets_before;
    s["four_boundary_tets_after"] = sp.four_boundary_tets_after;
    s["centroid_splits"] = sp.centroid_splits;
  }
  rep["refined"]["vertices"] = n;
  rep["refined"]["tets"] = m.num_tets();
  const double t_split = seconds_since(t0);

  // 2. boundary
  t0 = Clock::now();
  std::vector<int> face_tet;
  TriSurface surf;
  surf.vertices = m.vertices;
  surf.triangles = boundary_faces(m.tets, &face_tet);
  res.boundary = boundary_vertex_mask(n, surf.triangles);
  SphereMapResult sm = sphere_map(surf, opt);
  rep["boundary"] = sm.report;
  if (sm.flipped_triangles > 0)
    throw NumericalError("initial_map: the boundary map to the sphere flipped " +
                         std::to_string(sm.flipped_triangles) + " of " + std::to_string(surf.triangles.rows()) +
                         " triangles; " + quality_note());
  const double t_boundary = seconds_since(t0);

  // 3. harmonic interior
  t0 = Clock::now();
  // warm start: interior vertices at their input position mapped to the ball's scale
  FieldValues u = FieldValues::Zero(n, 3);
  {
    const Eigen::RowVector3d c = m.vertices.colwise().mean();
    const double r = (m.vertices.rowwise() - c).rowwise().norm().maxCoeff();
    for (int i = 0; i < n; ++i)
      u.row(i) = res.boundary[i] ? Eigen::RowVector3d(sm.sphere.row(i))
                                 : Eigen::RowVector3d((m.vertices.row(i) - c) / std::max(r, 1e-300));
  }
  // The shared Poisson solver (Jacobi CG on the host or the OpenCL device of `device`).
  SolverOptions so;
  so.relative_tolerance = opt.solver_tolerance;
  SolverStats st;
  try {
    PoissonSolver ps(device, n, m.tets, so);
    ps.set_positions(m.vertices);
    const FieldValues values = u;
    st = ps.solve_dirichlet(res.boundary, values, u);
  } catch (const NumericalError& e) {
    throw NumericalError(std::string("initial_map: the harmonic solve failed: ") + e.what() + "; " + quality_note());
  }
  if (!u.allFinite())
    throw NumericalError("initial_map: the harmonic solve gave non-finite positions; " + quality_note());
  rep["harmonic"]["solver"] = device.is_host() ? "PoissonSolver CG (host)" : "PoissonSolver CG (OpenCL)";
  rep["harmonic"]["iterations"] = st.iterations;
  rep["harmonic"]["relative_residual"] = st.relative_residual;
  res.ball = u;
  for (int i = 0; i < n; ++i)
    if (res.boundary[i]) res.ball.row(i) = sm.sphere.row(i);
  const int folds_harmonic = static_cast<int>(inverted_tets(res.ball, m.tets).size());
  rep["harmonic"]["inverted_tets"] = folds_harmonic;
  const double t_harmonic = seconds_since(t0);

  // 4. untangle
  t0 = Clock::now();
  rep["folds_before_untangle"] = folds_harmonic;
  int folds = folds_harmonic;
  if (opt.untangle == InitialMapOptions::Untangle::Always ||
      (opt.untangle == InitialMapOptions::Untangle::IfFolded && folds_harmonic > 0)) {
    const bool local = opt.untangle == InitialMapOptions::Untangle::IfFolded && opt.local_untangle_rings > 0;
    if (local) {
      // Few folds: free only their neighbourhood (fast); fall back to the global untangle.
      Points trial = res.ball;
      const UntangleResult ul = untangle_local(device, m.vertices, m.tets, trial, res.boundary,
                                               inverted_tets(res.ball, m.tets), opt.local_untangle_rings,
                                               opt.untangle_options);
      Json j = ul.to_json();
      j["scope"] = "local";
      j["rings"] = opt.local_untangle_rings;
      rep["untangle"] = j;
      folds = ul.inverted_after;
      if (folds == 0) res.ball = std::move(trial);
    }
    if (!local || folds > 0) {
      const UntangleResult ur = untangle(device, m.vertices, m.tets, res.ball, res.boundary, opt.untangle_options);
      Json j = ur.to_json();
      j["scope"] = "global";
      if (local) rep["untangle_local_failed"] = rep["untangle"];
      rep["untangle"] = j;
      folds = ur.inverted_after;
    }
  }
  rep["folds_after_untangle"] = folds;
  const double t_untangle = seconds_since(t0);

  // Boundary exactly on the sphere.
  double rad_err = 0;
  for (int i = 0; i < n; ++i)
    if (res.boundary[i]) rad_err = std::max(rad_err, std::abs(res.ball.row(i).norm() - 1.0));
  rep["boundary_max_radius_error"] = rad_err;

  if (folds > 0 && opt.throw_on_folds) {
    const std::vector<int> bad = inverted_tets(res.ball, m.tets);
    std::string where;
    for (size_t i = 0; i < bad.size() && i < 3; ++i) {
      const Eigen::Vector3d c = tet_centroid(m.vertices, m.tets, bad[i]);
      where += (i ? "; " : "") + std::string("tet ") + std::to_string(bad[i]) + " at (" + format_sig(c(0)) + ", " +
               format_sig(c(1)) + ", " + format_sig(c(2)) + ")";
    }
    throw NumericalError("initial_map: " + std::to_string(bad.size()) +
                         " tets remain folded after untangling (harmonic map folded " +
                         std::to_string(folds_harmonic) + "): " + where + "; " + quality_note());
  }
  t0 = Clock::now();
  const MapMetrics mm = map_metrics(device, m.vertices, res.ball, m.tets);
  rep["metrics"] = to_json(mm);
  Json& tm = rep["timings_s"];
  tm["input_quality"] = t_quality;
  tm["metrics"] = seconds_since(t0);
  tm["split"] = t_split;
  tm["boundary"] = t_boundary;
  tm["harmonic"] = t_harmonic;
  tm["untangle"] = t_untangle;
  tm["total"] = seconds_since(t_total);
  return res;
}

}  // namespace vpm
