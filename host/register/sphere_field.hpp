#pragma once
// The surface-divergence-free Gaussian field on the unit sphere shared by the landmark and the
// dense registrations (vpm/surface_registration.hpp): v(x) = x × sum_j H(x, y_j) u_j with
// H = grad_x grad_y^T exp(-lambda |x - y|^2), its Gram matrix, the exponential map, and the RK4
// advection of points through it (advect_on_sphere, host or device).
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "vpm/mesh.hpp"
#include "vpm/rbf.hpp"

namespace vpm {
class Device;
}

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

// Moves the unit rows of `x` through sphere fields: one (stationary) or 2K+1 (field s at time
// s / (2K)), each the SphereField of its centres and coefficients (u_j; the DivFreeField's kernel
// is not read), K RK4 steps of 1/K, each put back on the sphere: on `device` by
// kernels/register.cl's rk4_advect_soa (kernels/rbf_advect.clh, kind 2), on the host device by
// the same code on the host threads. Centres whose Gaussian is below e^-32 at a point are left
// out (host/register/advect.cpp).
void advect_on_sphere(Device& device, Points& x, const std::vector<DivFreeField>& fields, int steps);

// A field's centres and weights as advect_on_sphere's carrier, the weights scaled by `scale`.
inline DivFreeField carrier(double lambda, const std::vector<Vector3d>& centres, const std::vector<Vector3d>& weights,
                            double scale = 1) {
  DivFreeField d;
  d.lambda = lambda;
  d.centres = to_matrix(centres);
  d.coefficients = scale * to_matrix(weights);
  return d;
}
inline DivFreeField carrier(const SphereField& f, double scale = 1) { return carrier(f.lambda, f.centres, f.weights, scale); }

}  // namespace vpm::detail
