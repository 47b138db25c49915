#pragma once
// A smooth incompressible deformation for the paper's Table 1 (bench/paper.cpp) and its test
// (tests/test_geometry.cpp): the time-1 flow of the divergence-free field
//   u(x) = sum_k grad(phi_k)(x) x a_k = curl(sum_k phi_k a_k),  phi_k = exp(-|x - c_k|^2 / (2 s^2)).
// The flow of a divergence-free field preserves every volume; RK4 keeps that to its step error.
#include <cmath>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vpm::test {

struct IncompressibleFlow {
  std::vector<Eigen::Vector3d> centres, potentials;  ///< c_k, a_k
  double width = 1;                                  ///< s

  Eigen::Vector3d velocity(const Eigen::Vector3d& x) const {
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < centres.size(); ++k) {
      const Eigen::Vector3d d = x - centres[k];
      const Eigen::Vector3d grad = -d / (width * width) * std::exp(-d.squaredNorm() / (2 * width * width));
      u += grad.cross(potentials[k]);
    }
    return u;
  }

  /// x moved along the field from t = 0 to 1 (RK4, `steps` steps).
  Eigen::Vector3d flow(Eigen::Vector3d x, int steps = 20) const {
    const double h = 1.0 / steps;
    for (int i = 0; i < steps; ++i) {
      const Eigen::Vector3d k1 = velocity(x), k2 = velocity(x + 0.5 * h * k1), k3 = velocity(x + 0.5 * h * k2),
                            k4 = velocity(x + h * k3);
      x += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    return x;
  }
};

}  // namespace vpm::test
