#pragma once
// Gram matrices of the divergence-free kernels (vpm/rbf.hpp) shared by the fits: one 3 x 3 block
// per pair of centres.
#include <Eigen/Sparse>

#include "vpm/rbf.hpp"

namespace vpm {

/// K(x, y) of `kind` (3 x 3).
Eigen::Matrix3d kernel_block(RbfKernel kind, const Eigen::Vector3d& x, const Eigen::Vector3d& y, double lambda);

using SparseGram = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// The Gram matrix of the points `p` (3n x 3n, block (i, j) = K(p_i, p_j)) without the blocks of
/// pairs farther apart than 5 widths (lambda r^2 > 25, where psi < 1.4e-11).
SparseGram sparse_gram(const Points& p, RbfKernel kind, double lambda);

/// a x on the host threads (row blocks in parallel).
Eigen::VectorXd multiply(const SparseGram& a, const Eigen::VectorXd& x);

/// fit_divfree_weighted (vpm/rbf.hpp) with the centres' Gram matrix given (sparse_gram of
/// `centres` with options.kernel and lambda): fits at fixed centres share one.
DivFreeField fit_divfree_weighted(const Points& centres, const SparseGram& gram, const LocalSystems& local,
                                  const RbfFitOptions& options);

}  // namespace vpm
