#pragma once
// Compressed sparse row (CSR) matrices: the host form of every sparse operator in vpm
// (the cotangent Laplacian, Dirichlet-reduced systems), with conversions to and from Eigen.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace vpm {

/// Row-major sparse matrix in CSR form, 0-based, double values.
/// Row r holds the entries col[k], val[k] for k in [row_ptr[r], row_ptr[r+1]); within a row the
/// column indices are strictly increasing (no duplicates). Explicit zeros are allowed (the
/// Laplacian keeps its pattern even where a cotangent weight vanishes).
struct CsrMatrix {
  using EigenType = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

  int rows = 0;
  int cols = 0;
  std::vector<int> row_ptr;  ///< rows + 1 offsets into col/val; row_ptr[0] = 0
  std::vector<int> col;      ///< nnz column indices in [0, cols)
  std::vector<double> val;   ///< nnz values

  int nnz() const { return static_cast<int>(col.size()); }
  /// Index k into col/val of entry (r, c), or -1 if (r, c) is not in the pattern (binary search).
  int find(int r, int c) const;
  /// Value of entry (r, c); 0 when outside the pattern.
  double coeff(int r, int c) const;
  /// y = A x. x has length cols; returns length rows.
  Eigen::VectorXd multiply(const Eigen::VectorXd& x) const;
  /// Diagonal entries (length min(rows, cols); 0 where absent).
  Eigen::VectorXd diagonal() const;

  /// Compressed Eigen copy (explicit zeros kept).
  EigenType to_eigen() const;
  /// From any Eigen sparse matrix (row- or column-major, compressed or not). Duplicate entries
  /// must already be summed (Eigen guarantees that after setFromTriplets / makeCompressed).
  static CsrMatrix from_eigen(const EigenType& a);
  static CsrMatrix from_eigen(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& a);
};

}  // namespace vpm
