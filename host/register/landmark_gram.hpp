#pragma once
// Private: the linear algebra the surface registrations' landmark fields share
// (sphere_registration.cpp, disk_registration.cpp): the Cholesky factor of a landmark field's
// 2L x 2L Gram matrix and Rippa's leave-one-out error with 2 x 2 blocks.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <string>

#include "vpm/error.hpp"

namespace vpm::detail {

/// The factor of a landmark field's Gram matrix G; NumericalError naming `who` when G is not
/// positive definite.
inline Eigen::LLT<Eigen::MatrixXd> factor_gram(const Eigen::MatrixXd& G, const char* who) {
  Eigen::LLT<Eigen::MatrixXd> llt(G);
  if (llt.info() != Eigen::Success)
    throw NumericalError(std::string(who) +
                         ": the landmark field's Gram matrix is not positive definite (landmarks closer than round-off?)");
  return llt;
}

/// Leave-one-out error of the field that solves G a = b (L landmarks, two unknowns each): the root
/// mean square over landmarks of the block residuals [(G^-1)_ii]^-1 (G^-1 b)_i (Rippa's formula,
/// each landmark's value predicted from the others' without refitting).
inline double block_loo_error(const Eigen::MatrixXd& G, const Eigen::VectorXd& b, const char* who) {
  const Eigen::Index L = G.rows() / 2;
  const Eigen::MatrixXd inv = factor_gram(G, who).solve(Eigen::MatrixXd::Identity(2 * L, 2 * L));
  const Eigen::VectorXd a = inv * b;
  double sum = 0;
  for (Eigen::Index i = 0; i < L; ++i)
    sum += (Eigen::Matrix2d(inv.block<2, 2>(2 * i, 2 * i)).inverse() * a.segment<2>(2 * i)).squaredNorm();
  return std::sqrt(sum / static_cast<double>(L));
}

}  // namespace vpm::detail
