#include "register/rbf_gram.hpp"

#include <cmath>
#include <vector>

#include "core/parallel.hpp"
#include "register/point_bins.hpp"

namespace vpm {

Eigen::Matrix3d kernel_block(RbfKernel kind, const Eigen::Vector3d& x, const Eigen::Vector3d& y, double lambda) {
  return kind == RbfKernel::Free ? divfree_kernel(x - y, lambda) : tangent_kernel(x, y, lambda);
}

SparseGram sparse_gram(const Points& p, RbfKernel kind, double lambda) {
  const Eigen::Index n = p.rows();
  SparseGram a(3 * n, 3 * n);
  if (n == 0) return a;
  const double cut = 5 / std::sqrt(lambda);
  const PointBins bins(p, cut);
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index i = 0; i < n; ++i)
    bins.visit(p.row(i).transpose(), [&](int j) {
      if ((p.row(i) - p.row(j)).squaredNorm() * lambda > 25) return;
      const Eigen::Matrix3d k = kernel_block(kind, p.row(i).transpose(), p.row(j).transpose(), lambda);
      for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s) t.emplace_back(static_cast<int>(3 * i + r), 3 * j + s, k(r, s));
    });
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

Eigen::VectorXd multiply(const SparseGram& a, const Eigen::VectorXd& x) {
  Eigen::VectorXd y(a.rows());
  detail::parallel_for(static_cast<int>(a.rows()), 3000, [&](int begin, int end) {
    for (int r = begin; r < end; ++r) {
      double s = 0;
      for (SparseGram::InnerIterator it(a, r); it; ++it) s += it.value() * x(it.col());
      y(r) = s;
    }
  });
  return y;
}

}  // namespace vpm
