#include "vpm/sparse.hpp"

#include <algorithm>

namespace vpm {

int CsrMatrix::find(int r, int c) const {
  if (r < 0 || r >= rows) return -1;
  auto b = col.begin() + row_ptr[r], e = col.begin() + row_ptr[r + 1];
  auto it = std::lower_bound(b, e, c);
  return (it != e && *it == c) ? static_cast<int>(it - col.begin()) : -1;
}

double CsrMatrix::coeff(int r, int c) const {
  const int k = find(r, c);
  return k < 0 ? 0.0 : val[k];
}

Eigen::VectorXd CsrMatrix::multiply(const Eigen::VectorXd& x) const {
  Eigen::VectorXd y(rows);
  for (int r = 0; r < rows; ++r) {
    double s = 0;
    for (int k = row_ptr[r]; k < row_ptr[r + 1]; ++k) s += val[k] * x[col[k]];
    y[r] = s;
  }
  return y;
}

Eigen::VectorXd CsrMatrix::diagonal() const {
  Eigen::VectorXd d = Eigen::VectorXd::Zero(std::min(rows, cols));
  for (int r = 0; r < d.size(); ++r) d[r] = coeff(r, r);
  return d;
}

CsrMatrix::EigenType CsrMatrix::to_eigen() const {
  EigenType a(rows, cols);
  std::vector<int> counts(rows);
  for (int r = 0; r < rows; ++r) counts[r] = row_ptr[r + 1] - row_ptr[r];
  a.reserve(counts);
  for (int r = 0; r < rows; ++r)
    for (int k = row_ptr[r]; k < row_ptr[r + 1]; ++k) a.insert(r, col[k]) = val[k];
  a.makeCompressed();
  return a;
}

CsrMatrix CsrMatrix::from_eigen(const EigenType& in) {
  EigenType a = in;
  a.makeCompressed();
  CsrMatrix m;
  m.rows = static_cast<int>(a.rows());
  m.cols = static_cast<int>(a.cols());
  m.row_ptr.assign(a.outerIndexPtr(), a.outerIndexPtr() + m.rows + 1);
  m.col.assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
  m.val.assign(a.valuePtr(), a.valuePtr() + a.nonZeros());
  return m;
}

CsrMatrix CsrMatrix::from_eigen(const Eigen::SparseMatrix<double, Eigen::ColMajor, int>& a) {
  return from_eigen(EigenType(a));
}

}  // namespace vpm
