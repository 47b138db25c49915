#pragma once
// Private: one Gauss-Newton step of the dense registration on the sphere (sphere_match.cpp): the
// field's centres on an icosphere, the sparse system of the vertices' residuals and the held
// landmarks, its solution as a surface-divergence-free field, the advection through it.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

#include "register/dense_surface.hpp"
#include "register/point_bins.hpp"
#include "register/sphere_field.hpp"
#include "vpm/mesh.hpp"

namespace vpm::detail {

// Terms of the Gauss-Newton system with lambda |x - c|^2 beyond this are left out (below 1e-5
// of the peak; the step's direction only: the field itself uses every centre within
// kSphereCutoff).
constexpr double kSystemCutoff = 16;

/// The field's centres (an icosphere's vertices), their weight bases P_j, and their bins: the
/// centres within reach of a point (the system's 4 widths, the field's 6.3) without visiting all.
struct Centres {
  std::vector<Vector3d> c;
  std::vector<Eigen::Matrix<double, 3, 2>> P;
  double lambda = 1;
  PointBins system_bins, field_bins;
  Centres(const Points& at, double width);
  int size() const { return static_cast<int>(c.size()); }
};

/// A field of the centres, v(x) = x × sum_j H(x, c_j) u_j over the centres within reach.
struct BinnedField {
  const Centres* at = nullptr;
  std::vector<Vector3d> u;  ///< u_j = P_j a_j
  Vector3d operator()(const Vector3d& x) const;
};

/// The rows of the Gauss-Newton system: one a vertex of `x` (with the template's gradient
/// `grad` there), two a landmark (the field's tangent components, held at zero).
SparseRows system_rows(const std::vector<Vector3d>& x, const std::vector<Vector3d>& grad,
                       const std::vector<Vector3d>& landmarks, const Centres& cs);
/// The centres' Gram matrix (the field's smoothness), sparse.
Eigen::SparseMatrix<double> centre_gram(const Centres& cs);
/// The step's field: the weights minimising the weighted residuals plus ridge x the smoothness
/// (see sphere_step.cpp).
BinnedField gauss_newton_field(const SparseRows& J, const Eigen::VectorXd& area, const Eigen::VectorXd& e,
                               const Eigen::SparseMatrix<double>& K, const Centres& cs, double ridge);
/// Points moved through `alpha` x the stationary field on `device` (advect_on_sphere: two RK4
/// steps, each put back on the sphere).
std::vector<Vector3d> advected(Device& device, const std::vector<Vector3d>& x, const BinnedField& field, double alpha);
/// The largest |v| at the points.
double max_speed(const std::vector<Vector3d>& x, const BinnedField& field);

}  // namespace vpm::detail
