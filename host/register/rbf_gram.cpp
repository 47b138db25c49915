#include "register/rbf_gram.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "register/point_bins.hpp"
#include "vpm/error.hpp"

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
  // Each centre's near neighbours in increasing order (rows of blocks in parallel), then the
  // compressed rows written straight: the matrix setFromTriplets builds, without sorting
  // 9 x pairs triplets on one thread.
  std::vector<std::vector<int>> near(static_cast<size_t>(n));
  detail::parallel_for(static_cast<int>(n), 64, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      auto& js = near[static_cast<size_t>(i)];
      bins.visit(p.row(i).transpose(), [&](int j) {
        if ((p.row(i) - p.row(j)).squaredNorm() * lambda <= 25) js.push_back(j);
      });
      std::sort(js.begin(), js.end());
    }
  });
  std::vector<Eigen::Index> first(static_cast<size_t>(n) + 1, 0);  // of each row block's first entry
  for (Eigen::Index i = 0; i < n; ++i)
    first[static_cast<size_t>(i) + 1] = first[static_cast<size_t>(i)] + 9 * static_cast<Eigen::Index>(near[static_cast<size_t>(i)].size());
  if (first.back() > std::numeric_limits<int>::max())
    throw InputError("sparse_gram: " + std::to_string(n) + " centres at this width make more entries than one matrix holds");
  a.resizeNonZeros(first.back());
  int* outer = a.outerIndexPtr();
  for (Eigen::Index i = 0; i < n; ++i)
    for (int r = 0; r < 3; ++r)
      outer[3 * i + r] = static_cast<int>(first[static_cast<size_t>(i)] + 3 * r * static_cast<Eigen::Index>(near[static_cast<size_t>(i)].size()));
  outer[3 * n] = static_cast<int>(first.back());
  detail::parallel_for(static_cast<int>(n), 64, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      const auto& js = near[static_cast<size_t>(i)];
      for (size_t q = 0; q < js.size(); ++q) {
        const int j = js[q];
        const Eigen::Matrix3d k = kernel_block(kind, p.row(i).transpose(), p.row(j).transpose(), lambda);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) {
            const Eigen::Index at = outer[3 * i + r] + 3 * static_cast<Eigen::Index>(q) + c;
            a.innerIndexPtr()[at] = 3 * j + c;
            a.valuePtr()[at] = k(r, c);
          }
      }
    }
  });
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
