#include "linalg/csr_ops.hpp"

#include <algorithm>
#include <cstddef>

#include "core/parallel.hpp"

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

namespace {
// Rows per block of the products below: blocks run on the host threads; every row is computed
// the same way whichever thread takes it, so the results do not depend on the thread count.
constexpr int kRowsPerBlock = 4096;
}  // namespace

CsrMatrix spgemm_pattern(const CsrMatrix& a, const CsrMatrix& b) {
  CsrMatrix c;
  c.rows = a.rows;
  c.cols = b.cols;
  c.row_ptr.assign(a.rows + 1, 0);
  const int blocks = (a.rows + kRowsPerBlock - 1) / kRowsPerBlock;
  std::vector<std::vector<int>> cols(static_cast<size_t>(blocks));
  parallel_for(blocks, 2, [&](int b0, int b1) {
    std::vector<int> marker(static_cast<size_t>(b.cols), -1);
    for (int blk = b0; blk < b1; ++blk) {
      std::vector<int>& out = cols[static_cast<size_t>(blk)];
      for (int i = blk * kRowsPerBlock, e = std::min(a.rows, (blk + 1) * kRowsPerBlock); i < e; ++i) {
        const size_t start = out.size();
        for (int ka = a.row_ptr[i]; ka < a.row_ptr[i + 1]; ++ka) {
          const int k = a.col[ka];
          for (int kb = b.row_ptr[k]; kb < b.row_ptr[k + 1]; ++kb) {
            const int j = b.col[kb];
            if (marker[j] != i) {
              marker[j] = i;
              out.push_back(j);
            }
          }
        }
        std::sort(out.begin() + static_cast<std::ptrdiff_t>(start), out.end());
        c.row_ptr[i + 1] = static_cast<int>(out.size() - start);  // the row's length for now
      }
    }
  });
  for (int i = 0; i < a.rows; ++i) c.row_ptr[i + 1] += c.row_ptr[i];
  c.col.reserve(static_cast<size_t>(c.row_ptr[a.rows]));
  for (const std::vector<int>& block : cols) c.col.insert(c.col.end(), block.begin(), block.end());
  c.val.assign(c.col.size(), 0.0);
  return c;
}

void spgemm_values(const CsrMatrix& a, const CsrMatrix& b, CsrMatrix& c, std::vector<int>& pos) {
  const int blocks = (a.rows + kRowsPerBlock - 1) / kRowsPerBlock;
  pos.assign(static_cast<size_t>(b.cols), -1);  // the first thread's scratch; the others make their own
  parallel_for(blocks, 2, [&](int b0, int b1) {
    std::vector<int> own;
    if (b0 != 0) own.assign(static_cast<size_t>(b.cols), -1);
    std::vector<int>& where = b0 == 0 ? pos : own;
    for (int i = b0 * kRowsPerBlock, e = std::min(a.rows, b1 * kRowsPerBlock); i < e; ++i) {
      for (int q = c.row_ptr[i]; q < c.row_ptr[i + 1]; ++q) {
        where[c.col[q]] = q;
        c.val[q] = 0.0;
      }
      for (int ka = a.row_ptr[i]; ka < a.row_ptr[i + 1]; ++ka) {
        const int k = a.col[ka];
        const double av = a.val[ka];
        for (int kb = b.row_ptr[k]; kb < b.row_ptr[k + 1]; ++kb) c.val[where[b.col[kb]]] += av * b.val[kb];
      }
    }
  });
}

}  // namespace vpm::detail
