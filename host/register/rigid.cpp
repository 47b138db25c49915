// ---- rigid step ----
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "register/registration_steps.hpp"

namespace vpm {

Eigen::Matrix3d kabsch_rotation(const Points& from, const Points& to) {
  const Eigen::Matrix3d h = from.transpose() * to;  // sum p_i q_i^T
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d u = svd.matrixU(), v = svd.matrixV();
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((v * u.transpose()).determinant() < 0) d(2, 2) = -1;  // refuse the reflection
  return v * d * u.transpose();
}

double rotation_degrees(const Eigen::Matrix3d& rotation) {
  const double cosang = std::clamp((rotation.trace() - 1) / 2, -1.0, 1.0);
  return std::acos(cosang) * 180 / M_PI;
}

}  // namespace vpm
