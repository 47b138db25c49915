// The block products of the two solver backends (linalg/solver_backend.hpp).
#include "linalg/solver_backend.hpp"
#include "core/device_cl.hpp"

#include <stdexcept>

namespace vpm::detail {

namespace {
void check_block(int k) {
  if (k < 1 || k > kMaxBlock) throw std::logic_error("spmv_block: column count out of range");
}
}  // namespace

void HostBackend::spmv_block(HostBackend* const* columns, int k, Vec y, Vec x) {
  check_block(k);
  const HostBackend& b0 = *columns[0];
  const CsrMatrix& a = *b0.a_;
  double* yy[kMaxBlock];
  const double* xx[kMaxBlock];
  for (int c = 0; c < k; ++c) {
    yy[c] = columns[c]->v(y);
    xx[c] = columns[c]->v(x);
  }
  for (int i = 0; i < b0.n_; ++i) {
    double s[kMaxBlock] = {0, 0, 0};
    if (!b0.mask_[i])
      for (int q = a.row_ptr[i]; q < a.row_ptr[i + 1]; ++q)
        for (int c = 0; c < k; ++c) s[c] += a.val[q] * xx[c][a.col[q]];
    for (int c = 0; c < k; ++c) yy[c][i] = s[c];
  }
}

void ClBackend::spmv_block(ClBackend* const* columns, int k, Vec y, Vec x) {
  check_block(k);
  ClBackend& b0 = *columns[0];
  boost::compute::kernel& kr = b0.k_spmv_block_;
  kr.set_arg(5, k);
  for (int c = 0; c < kMaxBlock; ++c) {
    ClBackend& bc = *columns[c < k ? c : 0];
    kr.set_arg(6 + c, bc.vec_[x]);
    kr.set_arg(9 + c, bc.vec_[y]);
  }
  b0.dev_.cl().launch(kr, b0.n_);
}

}  // namespace vpm::detail
