#pragma once
// Points binned in a uniform grid of cubes, for the sums over near pairs of the dense
// registration (the sparse Gram matrix of the field's centres, the Gaussian average of the
// boundary matches).
#include <Eigen/Core>
#include <algorithm>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm {

/// The rows of `points` in cubes of side h >= `radius` over their bounding box (at most 129 a
/// side, whatever the radius), each cube listing its points in index order (a counting sort):
/// every point within `radius` of a query lies in the 27 cubes around the query's own.
class PointBins {
 public:
  PointBins(const Points& points, double radius) {
    const Eigen::Index n = points.rows();
    if (n > 0) {
      lo_ = points.colwise().minCoeff().transpose().array();
      const Eigen::Array3d span = points.colwise().maxCoeff().transpose().array() - lo_;
      h_ = std::max(radius, span.maxCoeff() / 128);
      dims_ = (span / h_).floor().cast<int>() + 1;
    } else {
      h_ = radius > 0 ? radius : 1.0;
    }
    const size_t cells = static_cast<size_t>(dims_(0)) * dims_(1) * dims_(2);
    start_.assign(cells + 1, 0);
    std::vector<size_t> cell(static_cast<size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) {
      cell[static_cast<size_t>(i)] = flat(cell_of(points.row(i).transpose()));
      ++start_[cell[static_cast<size_t>(i)] + 1];
    }
    for (size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
    order_.resize(static_cast<size_t>(n));
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (Eigen::Index i = 0; i < n; ++i) order_[static_cast<size_t>(fill[cell[static_cast<size_t>(i)]]++)] = static_cast<int>(i);
  }

  /// f(i) for every point i in the 27 cubes around `x` (cube by cube, index order within a cube);
  /// `x` may lie outside the points' box.
  template <class F>
  void visit(const Eigen::Vector3d& x, F&& f) const {
    const Eigen::Array3i k = cell_of(x);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const Eigen::Array3i d = k + Eigen::Array3i(dx, dy, dz);
          if ((d < 0).any() || (d >= dims_).any()) continue;
          const size_t q = flat(d);
          for (int j = start_[q]; j < start_[q + 1]; ++j) f(order_[static_cast<size_t>(j)]);
        }
  }

 private:
  Eigen::Array3i cell_of(const Eigen::Vector3d& x) const {  // -1 and dims: outside the box
    return ((x.array() - lo_) / h_).floor().max(-1.0).min(dims_.cast<double>()).cast<int>();
  }
  size_t flat(const Eigen::Array3i& c) const {
    return static_cast<size_t>(c(0)) + static_cast<size_t>(dims_(0)) * (static_cast<size_t>(c(1)) + static_cast<size_t>(dims_(1)) * static_cast<size_t>(c(2)));
  }

  Eigen::Array3d lo_ = Eigen::Array3d::Zero();
  Eigen::Array3i dims_ = Eigen::Array3i::Ones();
  double h_ = 1;
  std::vector<int> start_, order_;
};

}  // namespace vpm
