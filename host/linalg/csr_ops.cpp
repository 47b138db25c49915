#include "linalg/csr_ops.hpp"

#include <algorithm>

namespace vpm::detail {

CsrMatrix csr_transpose(const CsrMatrix& a) {
  CsrMatrix t;
  t.rows = a.cols;
  t.cols = a.rows;
  t.row_ptr.assign(t.rows + 1, 0);
  for (int c : a.col) ++t.row_ptr[c + 1];
  for (int i = 0; i < t.rows; ++i) t.row_ptr[i + 1] += t.row_ptr[i];
  t.col.resize(a.col.size());
  t.val.resize(a.val.size());
  std::vector<int> next(t.row_ptr.begin(), t.row_ptr.end() - 1);
  for (int r = 0; r < a.rows; ++r)
    for (int k = a.row_ptr[r]; k < a.row_ptr[r + 1]; ++k) {
      const int q = next[a.col[k]]++;
      t.col[q] = r;
      t.val[q] = a.val[k];
    }
  return t;
}

CsrMatrix spgemm_pattern(const CsrMatrix& a, const CsrMatrix& b) {
  CsrMatrix c;
  c.rows = a.rows;
  c.cols = b.cols;
  c.row_ptr.assign(a.rows + 1, 0);
  std::vector<int> marker(b.cols, -1);
  for (int i = 0; i < a.rows; ++i) {
    const size_t start = c.col.size();
    for (int ka = a.row_ptr[i]; ka < a.row_ptr[i + 1]; ++ka) {
      const int k = a.col[ka];
      for (int kb = b.row_ptr[k]; kb < b.row_ptr[k + 1]; ++kb) {
        const int j = b.col[kb];
        if (marker[j] != i) {
          marker[j] = i;
          c.col.push_back(j);
        }
      }
    }
    std::sort(c.col.begin() + start, c.col.end());
    c.row_ptr[i + 1] = static_cast<int>(c.col.size());
  }
  c.val.assign(c.col.size(), 0.0);
  return c;
}

void spgemm_values(const CsrMatrix& a, const CsrMatrix& b, CsrMatrix& c, std::vector<int>& pos) {
  pos.assign(b.cols, -1);
  for (int i = 0; i < a.rows; ++i) {
    for (int q = c.row_ptr[i]; q < c.row_ptr[i + 1]; ++q) {
      pos[c.col[q]] = q;
      c.val[q] = 0.0;
    }
    for (int ka = a.row_ptr[i]; ka < a.row_ptr[i + 1]; ++ka) {
      const int k = a.col[ka];
      const double av = a.val[ka];
      for (int kb = b.row_ptr[k]; kb < b.row_ptr[k + 1]; ++kb) c.val[pos[b.col[kb]]] += av * b.val[kb];
    }
  }
}

}  // namespace vpm::detail
