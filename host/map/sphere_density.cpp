// Equal-area correction of a sphere map (map/sphere_steps.hpp): a log-density Moser flow on the
// sphere.
//
// The conformal sphere map gives a protrusion of aspect A a spherical cap whose area falls like
// exp(-2 pi A): limbs and fingers arrive on the sphere e^-20..e^-40 too small, and neither the
// interior map nor the Moser rounds in the ball recover from that. Here the sphere points move
// along v = grad u, where on the current sphere mesh
//     Laplace u = g,   g_t = log(T_t / c_t) - (its area-weighted mean)
// (c_t: the triangle's chord area, T_t: its share of the input's area times the sphere's), so
// the flow's divergence is the log of the area deficit: a triangle e^-40 too small grows by a
// factor e per unit of (dt * g), whatever its size (the cotangent Laplacian is scale-free), and
// the log ratios decay like e^-t. Each step is one solve with the Laplacian
// (map/density_solve.hpp); dt = 0.5 / max |g|, halved until no triangle flips and the area-weighted mean square
// of g falls. Stops when the area distortion reaches `tolerance`, stalls, or after max_steps.
//
// A stretch-energy fixed point (Yueh et al. 2019) in a stereographic chart was tried first and
// dropped: from e^-40 its preconditioned steps overshoot (energy x250, flips) and the line
// search crawls (1e-3 per iteration on the limbs).
#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <vector>

#include "map/density_solve.hpp"
#include "map/sphere_steps.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/timing.hpp"

namespace vpm::detail {

namespace {

using Trip = Eigen::Triplet<double>;

Eigen::VectorXd chord_areas(const Points& s, const Triangles& f) {
  Eigen::VectorXd c(f.rows());
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const Eigen::Vector3d a = s.row(f(t, 0)), b = s.row(f(t, 1)), d = s.row(f(t, 2));
    c(t) = 0.5 * (b - a).cross(d - a).norm();
  }
  return c;
}

// Per vertex (lumped over its triangles, which smooths the mesh-scale noise of single
// triangles): g_i = log(T_i / c_i) with T = share * sum(c), minus its c-weighted mean (so the
// Poisson problem on the closed surface is solvable); *misfit = the c-weighted mean of g^2
// before centring (0 exactly at equal areas). Also returns the lumped areas in *ci.
Eigen::VectorXd log_deficit(const Triangles& f, int k, const Eigen::VectorXd& c, const Eigen::VectorXd& share,
                            double* misfit, Eigen::VectorXd* ci) {
  const double total = c.sum();
  Eigen::VectorXd cv = Eigen::VectorXd::Zero(k);
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int j = 0; j < 3; ++j) cv(f(t, j)) += c(t) / 3;
  const Eigen::VectorXd tv = share * total;
  Eigen::VectorXd g(k);
  double mean = 0, sq = 0;
  for (int i = 0; i < k; ++i) {
    g(i) = std::clamp(std::log(std::max(tv(i), 1e-300) / std::max(cv(i), 1e-300)), -60.0, 60.0);
    mean += cv(i) * g(i);
    sq += cv(i) * g(i) * g(i);
  }
  if (misfit) *misfit = sq / total;
  g.array() -= mean / total;
  if (ci) *ci = cv;
  return g;
}

// The cotangent Laplacian of the chord triangles with vertex 0 pinned (row and column removed),
// as triplets in a fixed order so the sparsity pattern is the same at every step.
SpMat pinned_laplacian(const Points& s, const Triangles& f) {
  const int k = static_cast<int>(s.rows());
  std::vector<Trip> trips;
  trips.reserve(12 * f.rows());
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int j = 0; j < 3; ++j) {
      const int o = f(t, j), a = f(t, (j + 1) % 3), b = f(t, (j + 2) % 3);
      const Eigen::Vector3d u = s.row(a) - s.row(o), w = s.row(b) - s.row(o);
      const double w2 = 0.5 * u.dot(w) / std::max(u.cross(w).norm(), 1e-300);
      const int ia = a - 1, ib = b - 1;  // vertex 0 pinned
      if (ia >= 0) trips.emplace_back(ia, ia, w2);
      if (ib >= 0) trips.emplace_back(ib, ib, w2);
      if (ia >= 0 && ib >= 0) {
        trips.emplace_back(ia, ib, -w2);
        trips.emplace_back(ib, ia, -w2);
      }
    }
  SpMat L(k - 1, k - 1);
  L.setFromTriplets(trips.begin(), trips.end());
  return L;
}

// The flow's velocity: grad u per chord triangle, averaged to the vertices with the triangle
// areas, projected to the tangent planes.
Points velocity(const Points& s, const Triangles& f, const Eigen::VectorXd& c, const Eigen::VectorXd& u) {
  const int k = static_cast<int>(s.rows());
  Points v = Points::Zero(k, 3);
  Eigen::VectorXd wsum = Eigen::VectorXd::Zero(k);
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const int id[3] = {f(t, 0), f(t, 1), f(t, 2)};
    const Eigen::Vector3d p0 = s.row(id[0]), p1 = s.row(id[1]), p2 = s.row(id[2]);
    Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    const double a2 = n.norm();
    if (!(a2 > 0)) continue;
    n /= a2;
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d e = s.row(id[(j + 2) % 3]) - s.row(id[(j + 1) % 3]);
      g += u(id[j]) * n.cross(e) / a2;
    }
    for (int j = 0; j < 3; ++j) {
      v.row(id[j]) += c(t) * g.transpose();
      wsum(id[j]) += c(t);
    }
  }
  for (int i = 0; i < k; ++i) {
    if (wsum(i) > 0) v.row(i) /= wsum(i);
    const Eigen::Vector3d x = s.row(i);
    v.row(i) -= v.row(i).dot(x) * x.transpose();
  }
  return v;
}

// A step s + dt v that flips a triangle the current map does not flip: such a triangle (a
// sliver on the sphere that the mesh-scale variation of v would turn over) is moved rigidly,
// its corners taking their mean velocity; repeated (the change spreads to neighbours) up to
// 8 times. Returns the step, or an empty matrix when flips remain.
Points rigid_where_flipped(const Points& s, const Triangles& f, Points& v, double dt) {
  for (int pass = 0; pass < 8; ++pass) {
    Points q = s + dt * v;
    normalize_rows(q);
    bool any = false;
    for (Eigen::Index t = 0; t < f.rows(); ++t) {
      const Eigen::Vector3d a = q.row(f(t, 0)), b = q.row(f(t, 1)), d = q.row(f(t, 2));
      const Eigen::Vector3d a0 = s.row(f(t, 0)), b0 = s.row(f(t, 1)), d0 = s.row(f(t, 2));
      if (a.dot(b.cross(d)) > 0 || !(a0.dot(b0.cross(d0)) > 0)) continue;
      any = true;
      const Eigen::RowVector3d mean = (v.row(f(t, 0)) + v.row(f(t, 1)) + v.row(f(t, 2))) / 3;
      for (int j = 0; j < 3; ++j) v.row(f(t, j)) = mean;
    }
    if (!any) return q;
  }
  return Points();
}

}  // namespace

Eigen::VectorXd vertex_area_shares(const Points& in, const Triangles& f) {
  Eigen::VectorXd share = Eigen::VectorXd::Zero(in.rows());
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const Eigen::Vector3d a = in.row(f(t, 0)), b = in.row(f(t, 1)), d = in.row(f(t, 2));
    const double area = 0.5 * (b - a).cross(d - a).norm();
    for (int j = 0; j < 3; ++j) share(f(t, j)) += area / 3;
  }
  return share / share.sum();
}

EquiarealStats equalise_density(const Points& in, const Triangles& f, const Eigen::VectorXd& target, Points& s,
                                int max_steps, double tolerance, Device* device) {
  EquiarealStats st;
  const int k = static_cast<int>(s.rows());
  Eigen::VectorXd share = target.cwiseMax(1e-300 * target.maxCoeff());
  share /= share.sum();
  st.distortion_before = st.distortion_after = area_distortion(in, s, f);
  st.flips_before = flipped_sphere_triangles(s, f);
  if (k < 4) return st;
  Eigen::VectorXd c = chord_areas(s, f);
  double misfit = 0;
  Eigen::VectorXd cv;
  Eigen::VectorXd g = log_deficit(f, k, c, share, &misfit, &cv);
  st.misfit_before = st.misfit_after = misfit;
  DensitySolver solver(device);
  int stalled = 0;
  double best = st.distortion_before;
  for (int step = 0; step < max_steps && st.distortion_after > tolerance; ++step) {
    const SpMat L = pinned_laplacian(s, f);
    // -L u = M g (M: lumped vertex areas), u(0) = 0
    const Eigen::VectorXd rhs = -cv.cwiseProduct(g);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(k);
    Eigen::VectorXd tail;
    const auto t_solve = Clock::now();
    const bool solved = solver.solve(L, rhs.tail(k - 1), tail);
    st.solve_seconds += seconds_since(t_solve);
    if (!solved) break;
    u.tail(k - 1) = tail;
    if (!u.allFinite()) break;
    Points v = velocity(s, f, c, u);
    double dt = 0.5 / std::max(g.cwiseAbs().maxCoeff(), 1e-12);
    const int flips = flipped_sphere_triangles(s, f);
    bool moved = false;
    for (int halving = 0; halving < 12 && !moved; ++halving, dt *= 0.5) {
      Points q = s + dt * v;
      normalize_rows(q);
      if (!q.allFinite()) continue;
      if (flipped_sphere_triangles(q, f) > flips) {
        q = rigid_where_flipped(s, f, v, dt);
        if (q.rows() == 0) continue;
      }
      const Eigen::VectorXd cq = chord_areas(q, f);
      double mq = 0;
      Eigen::VectorXd cvq;
      const Eigen::VectorXd gq = log_deficit(f, k, cq, share, &mq, &cvq);
      if (!(mq < misfit)) continue;
      s = std::move(q);
      c = cq;
      cv = cvq;
      g = gq;
      misfit = mq;
      moved = true;
    }
    if (!moved) break;
    ++st.steps;
    st.distortion_after = area_distortion(in, s, f);
    if (st.distortion_after < best * (1 - 2e-3)) {
      best = st.distortion_after;
      stalled = 0;
    } else if (++stalled >= 5) {
      break;
    }
  }
  st.misfit_after = misfit;
  st.solver = solver.name();
  return st;
}

}  // namespace vpm::detail
