#include "register/rbf_gram.hpp"

#include <cmath>
#include <vector>

#include "core/parallel.hpp"

namespace vpm {

Eigen::Matrix3d kernel_block(RbfKernel kind, const Eigen::Vector3d& x, const Eigen::Vector3d& y, double lambda) {
  return kind == RbfKernel::Free ? divfree_kernel(x - y, lambda) : tangent_kernel(x, y, lambda);
}

SparseGram sparse_gram(const Points& p, RbfKernel kind, double lambda) {
  const Eigen::Index n = p.rows();
  SparseGram a(3 * n, 3 * n);
  if (n == 0) return a;
  const double cut = 5 / std::sqrt(lambda);
  // bin the points into cells of size `cut`: neighbours lie in the 27 cells around
  const Eigen::Vector3d lo = p.colwise().minCoeff().transpose();
  const Eigen::Array3i dims = (((p.colwise().maxCoeff().transpose() - lo) / cut).array().floor().cast<int>() + 1);
  auto cell_of = [&](Eigen::Index i) -> Eigen::Array3i {
    return ((p.row(i).transpose() - lo) / cut).array().floor().cast<int>().min(dims - 1);
  };
  std::vector<std::vector<int>> cells(static_cast<size_t>(dims.prod()));
  auto flat = [&](const Eigen::Array3i& c) { return static_cast<size_t>(c(0) + dims(0) * (c(1) + dims(1) * c(2))); };
  for (Eigen::Index i = 0; i < n; ++i) cells[flat(cell_of(i))].push_back(static_cast<int>(i));
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Array3i c = cell_of(i);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const Eigen::Array3i d = c + Eigen::Array3i(dx, dy, dz);
          if ((d < 0).any() || (d >= dims).any()) continue;
          for (int j : cells[flat(d)]) {
            if ((p.row(i) - p.row(j)).squaredNorm() * lambda > 25) continue;
            const Eigen::Matrix3d k = kernel_block(kind, p.row(i).transpose(), p.row(j).transpose(), lambda);
            for (int r = 0; r < 3; ++r)
              for (int s = 0; s < 3; ++s) t.emplace_back(static_cast<int>(3 * i + r), 3 * j + s, k(r, s));
          }
        }
  }
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
