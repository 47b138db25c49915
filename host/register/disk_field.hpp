#pragma once
// Private: the divergence-free field in the unit disk tangent to its circle, shared by the
// landmark and the dense registrations in the disk (vpm/surface_registration.hpp,
// register_in_disk): v = J grad psi (J the quarter turn) with the stream function
// psi(x) = s(x) sum_j b_j . grad_y [s(y) exp(-lambda |x - y|^2)] at y = y_j, s(x) = 1 - |x|^2.
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "vpm/mesh.hpp"
#include "vpm/rbf.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

using Eigen::Matrix2d;
using Eigen::Vector2d;

/// Terms with lambda |x - y|^2 beyond this are below 1e-17 of the peak and skipped.
constexpr double kDiskCutoff = 40;

/// J, the quarter turn: v = J grad psi.
inline Matrix2d quarter_turn() { return (Matrix2d() << 0, 1, -1, 0).finished(); }

/// M(x, y) = grad_x grad_y^T of the stream-function kernel s(x) s(y) exp(-lambda |x - y|^2):
/// zero stream function on the circle, so every field J sum_j M(x, y_j) b_j is divergence-free
/// and tangent to the circle. M(y, x) = M(x, y)^T; the blocks M(y_j, y_k) form a positive
/// semi-definite Gram matrix (the field's smoothness).
inline Matrix2d stream_hessian(const Vector2d& x, const Vector2d& y, double lambda) {
  const Vector2d r = x - y;
  const double k = std::exp(-lambda * r.squaredNorm()), sx = 1 - x.squaredNorm(), sy = 1 - y.squaredNorm();
  return k * (4 * x * y.transpose() - 4 * lambda * sy * x * r.transpose() + 4 * lambda * sx * r * y.transpose() +
              sx * sy * (2 * lambda * Matrix2d::Identity() - 4 * lambda * lambda * r * r.transpose()));
}

/// The field of the centres y_j with coefficients b_j (every centre visited: for the landmark
/// fields, a few dozen).
struct DiskField {
  double lambda = 1;
  std::vector<Vector2d> centres, weights;  // y_j, b_j
  Vector2d operator()(const Vector2d& x) const {
    Vector2d w = Vector2d::Zero();
    for (size_t j = 0; j < centres.size(); ++j)
      if (lambda * (x - centres[j]).squaredNorm() <= kDiskCutoff) w += stream_hessian(x, centres[j], lambda) * weights[j];
    return quarter_turn() * w;
  }
};

/// x put on the domain: the boundary loop's vertices (boundary[i] = 1; may be shorter than x)
/// onto the circle, every other point outside it back onto it.
inline void place_in_disk(std::vector<Vector2d>& x, const std::vector<char>& boundary) {
  for (size_t i = 0; i < x.size(); ++i) {
    const double r = x[i].norm();
    if ((i < boundary.size() && boundary[i]) || r > 1) x[i] /= r;
  }
}

/// The rows (x, y, 0) of the points, and back.
inline Points disk_points(const std::vector<Vector2d>& x) {
  Points m(static_cast<Eigen::Index>(x.size()), 3);
  for (size_t i = 0; i < x.size(); ++i) m.row(static_cast<Eigen::Index>(i)) << x[i].x(), x[i].y(), 0.0;
  return m;
}
inline std::vector<Vector2d> disk_vectors(const Points& m) {
  std::vector<Vector2d> v(static_cast<size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) v[static_cast<size_t>(i)] = Vector2d(m(i, 0), m(i, 1));
  return v;
}

/// A field's centres and coefficients (as rows (x, y, 0)) as advect_in_disk's carrier, the
/// coefficients scaled by `scale`.
inline DivFreeField disk_carrier(double lambda, const std::vector<Vector2d>& centres, const std::vector<Vector2d>& weights,
                                 double scale = 1) {
  DivFreeField d;
  d.lambda = lambda;
  d.centres = disk_points(centres);
  d.coefficients = scale * disk_points(weights);
  return d;
}
inline DivFreeField disk_carrier(const DiskField& f) { return disk_carrier(f.lambda, f.centres, f.weights); }

/// Moves the points (rows (x, y, 0)) through disk fields: one (stationary) or 2K+1 (field s at
/// time s / (2K)), K RK4 steps of 1/K, points outside the circle put back on it after each: on
/// `device` by kernels/register.cl's rk4_advect_soa (kernels/rbf_advect.clh, kind 3), on the host
/// device by the same code on the host threads (host/register/advect.cpp).
void advect_in_disk(Device& device, Points& x, const std::vector<DivFreeField>& fields, int steps);

/// The same for 2-D points, then the boundary loop's vertices (boundary[i] = 1) put back on the
/// circle (place_in_disk).
inline void advect_in_disk(Device& device, std::vector<Vector2d>& x, const std::vector<DivFreeField>& fields, int steps,
                           const std::vector<char>& boundary) {
  Points m = disk_points(x);
  advect_in_disk(device, m, fields, steps);
  x = disk_vectors(m);
  place_in_disk(x, boundary);
}

}  // namespace vpm::detail
