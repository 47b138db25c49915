#pragma once
// Private: the dense (pseudo-)inverse of the coarsest multigrid level (linalg/amg.cpp).
#include <Eigen/Core>
#include <vector>

#include "vpm/sparse.hpp"

namespace vpm::detail {

/// Dense inverse of the symmetric matrix `a` restricted to the active rows and columns (`act`
/// non-zero), zero in inactive rows and columns. When every active row sums to zero (a
/// Neumann operator: constants in the null space) it is the pseudo-inverse, computed by LDLT
/// of A + s u u^T (u: unit constant on the active rows, s: the mean diagonal) minus u u^T / s.
/// If the LDLT is numerically singular (e.g. several components), falls back to a symmetric
/// eigen-decomposition with eigenvalues below 1e-10 max |lambda| dropped.
Eigen::MatrixXd coarse_pseudo_inverse(const CsrMatrix& a, const std::vector<char>& act);

}  // namespace vpm::detail
