#include "linalg/amg_coarse.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>

namespace vpm::detail {

Eigen::MatrixXd coarse_pseudo_inverse(const CsrMatrix& a, const std::vector<char>& act) {
  const int n = a.rows;
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n, n);
  int count = 0;
  double trace = 0;
  bool zero_sums = true;
  for (int i = 0; i < n; ++i) {
    if (!act[i]) {
      m(i, i) = 1.0;
      continue;
    }
    ++count;
    double sum = 0, dia = 0;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) {
      const int j = a.col[k];
      if (!act[j]) continue;
      m(i, j) = a.val[k];
      sum += a.val[k];
      if (j == i) dia = a.val[k];
    }
    trace += dia;
    if (std::abs(sum) > 1e-8 * std::abs(dia)) zero_sums = false;
  }
  m = 0.5 * (m + m.transpose()).eval();
  const bool neumann = zero_sums && count > 0 && trace != 0;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  const double s = neumann ? trace / count : 0.0;
  if (neumann) {
    for (int i = 0; i < n; ++i) u[i] = act[i] ? 1.0 / std::sqrt(double(count)) : 0.0;
    m.noalias() += s * u * u.transpose();
  }
  Eigen::MatrixXd inv;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(m);
  const Eigen::VectorXd D = ldlt.vectorD().cwiseAbs();
  if (ldlt.info() == Eigen::Success && n > 0 && D.minCoeff() > 1e-12 * D.maxCoeff()) {
    inv = ldlt.solve(Eigen::MatrixXd::Identity(n, n));
    if (neumann) inv.noalias() -= (1.0 / s) * u * u.transpose();
  } else {
    if (neumann) m.noalias() -= s * u * u.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(m);
    const Eigen::VectorXd& lam = es.eigenvalues();
    const double cut = 1e-10 * (n > 0 ? lam.cwiseAbs().maxCoeff() : 0.0);
    Eigen::VectorXd inv_lam(n);
    for (int i = 0; i < n; ++i) inv_lam[i] = std::abs(lam[i]) > cut ? 1.0 / lam[i] : 0.0;
    inv = es.eigenvectors() * inv_lam.asDiagonal() * es.eigenvectors().transpose();
  }
  for (int i = 0; i < n; ++i)
    if (!act[i]) {
      inv.row(i).setZero();
      inv.col(i).setZero();
    }
  return 0.5 * (inv + inv.transpose());
}

}  // namespace vpm::detail
