#pragma once
// The surface-divergence-free Gaussian field on the unit sphere shared by the landmark and the
// dense registrations (vpm/surface_registration.hpp): v(x) = x × sum_j H(x, y_j) u_j with
// H = grad_x grad_y^T exp(-lambda |x - y|^2), its Gram matrix, the exponential map, and the RK4
// advection of points through it.
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "core/parallel.hpp"
#include "vpm/mesh.hpp"

namespace vpm::detail {

using Eigen::Vector3d;

// Terms with lambda |x - y|^2 beyond this are below 1e-17 of the peak and skipped.
constexpr double kSphereCutoff = 40;

// H(x, y) = e (2 lambda I - 4 lambda^2 r r^T), r = x - y, e = exp(-lambda |r|^2).
inline Eigen::Matrix3d gaussian_hessian(const Vector3d& r, double lambda) {
  const double e = std::exp(-lambda * r.squaredNorm());
  return e * (2 * lambda * Eigen::Matrix3d::Identity() - 4 * lambda * lambda * r * r.transpose());
}

struct SphereField {
  double lambda = 1;
  std::vector<Vector3d> centres, weights;  // y_j, u_j (tangent at y_j)

  Vector3d operator()(const Vector3d& x) const {
    Vector3d w = Vector3d::Zero();
    for (size_t j = 0; j < centres.size(); ++j) {
      const Vector3d r = x - centres[j];
      const double s = lambda * r.squaredNorm();
      if (s > kSphereCutoff) continue;
      const double e = std::exp(-s);
      w += e * (2 * lambda * weights[j] - 4 * lambda * lambda * r * r.dot(weights[j]));
    }
    return x.cross(w);
  }
};

// The rows of m as unit vectors, and back.
inline std::vector<Vector3d> unit_rows(const Points& m) {
  std::vector<Vector3d> v(static_cast<size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) v[static_cast<size_t>(i)] = m.row(i).transpose().normalized();
  return v;
}
inline Points to_matrix(const std::vector<Vector3d>& v) {
  Points m(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  return m;
}

// An orthonormal basis of the plane tangent to the unit sphere at x (3 x 2).
inline Eigen::Matrix<double, 3, 2> tangent_basis(const Vector3d& x) {
  const Vector3d a = std::abs(x.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
  const Vector3d e1 = (a - x * x.dot(a)).normalized();
  Eigen::Matrix<double, 3, 2> b;
  b << e1, x.cross(e1);
  return b;
}

// P = [x]×^T B at a centre x: u = P a is the weight whose field at x is B a (the Gram's basis).
inline Eigen::Matrix<double, 3, 2> weight_basis(const Vector3d& x) {
  const Eigen::Matrix<double, 3, 2> b = tangent_basis(x);
  Eigen::Matrix<double, 3, 2> p;
  for (int k = 0; k < 2; ++k) p.col(k) = -x.cross(b.col(k));
  return p;
}

// exp_x(v): the point at angular distance |v| from x in direction v (v tangent at x).
inline Vector3d exp_map(const Vector3d& x, const Vector3d& v) {
  const double a = v.norm();
  return a < 1e-300 ? x : Vector3d(std::cos(a) * x + std::sin(a) * v / a);
}

// log_x(q): the tangent vector at x toward q of length the angle between them.
inline Vector3d log_map(const Vector3d& x, const Vector3d& q) {
  const Vector3d t = q - x * x.dot(q);
  const double n = t.norm();
  return n < 1e-300 ? Vector3d::Zero() : Vector3d(std::atan2(n, x.dot(q)) * t / n);
}

// One RK4 step of dt from t for every point of x (in place), fields at t, t + dt/2, t + dt;
// the points put back on the sphere against round-off.
inline void rk4_step(std::vector<Vector3d>& x, const SphereField& f0, const SphereField& fh, const SphereField& f1, double dt) {
  parallel_for(static_cast<int>(x.size()), 256, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      const Vector3d k1 = f0(x[i]);
      const Vector3d k2 = fh(x[i] + dt / 2 * k1);
      const Vector3d k3 = fh(x[i] + dt / 2 * k2);
      const Vector3d k4 = f1(x[i] + dt * k3);
      x[i] = (x[i] + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)).normalized();
    }
  });
}

}  // namespace vpm::detail
