#include "linalg/amg_device.hpp"
#include "core/device_cl.hpp"

#include <algorithm>

namespace vpm::detail {

namespace bc = boost::compute;

ClAmg::ClAmg(Device& dev) : dev_(dev), coarse_inv_(dev.cl().context) {
  auto K = [&](const char* name) { return dev.cl().kernel("amg", name); };
  k_first_ = K("amg_first");
  k_scale_ = K("amg_scale");
  k_sweep_ = K("amg_sweep");
  k_residual_ = K("amg_residual");
  k_spmv_ = K("amg_spmv");
  k_prolong_ = K("amg_prolong");
  k_dense_ = K("amg_dense");
}

namespace {
template <class T>
void put(bc::vector<T>& dst, const std::vector<T>& src, bool resize, bc::command_queue& q) {
  if (resize || dst.size() < std::max<size_t>(src.size(), 1)) dst = bc::vector<T>(std::max<size_t>(src.size(), 1), q.get_context());
  if (!src.empty()) bc::copy(src.begin(), src.end(), dst.begin(), q);
}
}  // namespace

void ClAmg::upload_csr(const CsrMatrix& m, Csr& c, bool pattern) {
  auto& q = dev_.cl().queue;
  if (pattern) {
    put(c.row_ptr, m.row_ptr, true, q);
    put(c.col, m.col, true, q);
  }
  put(c.val, m.val, pattern, q);
  c.rows = m.rows;
}

void ClAmg::upload(const AmgHierarchy& h, bool pattern) {
  auto& q = dev_.cl().queue;
  auto& ctx = dev_.cl().context;
  pattern = pattern || num_levels() != h.num_levels();
  for (int l = 0; l < h.num_levels() && !pattern; ++l)
    pattern = levels_[l].n != h.level(l).A.rows || levels_[l].A.val.size() != std::max<size_t>(h.level(l).A.val.size(), 1) ||
              levels_[l].P.val.size() != std::max<size_t>(h.level(l).P.val.size(), 1);
  sweeps_ = h.options().sweeps;
  if (pattern) levels_.clear();
  levels_.resize(h.num_levels());
  for (int l = 0; l < h.num_levels(); ++l) {
    const AmgLevel& src = h.level(l);
    Level& lv = levels_[l];
    lv.n = src.A.rows;
    const size_t nn = std::max(1, lv.n);
    if (pattern) {
      for (auto* v : {&lv.f, &lv.out, &lv.x, &lv.r, &lv.t}) *v = bc::vector<double>(nn, ctx);
    }
    const bool coarsest = l + 1 == h.num_levels();
    if (!coarsest) {
      upload_csr(src.A, lv.A, pattern);
      upload_csr(src.P, lv.P, pattern);
      upload_csr(src.R, lv.R, pattern);
      put(lv.d, src.d, pattern, q);
    }
  }
  // the coarse inverse is symmetric: its row-major layout equals Eigen's column-major storage
  const Eigen::MatrixXd& m = h.coarse_inverse();
  const std::vector<double> inv(m.data(), m.data() + m.size());
  put(coarse_inv_, inv, pattern, q);
}

void ClAmg::apply(bc::vector<double>& f, bc::vector<double>& z) { vcycle(0, f, z); }

void ClAmg::vcycle(int l, bc::vector<double>& f, bc::vector<double>& out) {
  Level& lv = levels_[l];
  const int n = lv.n;
  if (l + 1 == num_levels()) {
    k_dense_.set_args(n, coarse_inv_, f, out);
    dev_.cl().launch(k_dense_, n);
    return;
  }
  const Csr& A = lv.A;
  bc::vector<double>*x = &lv.x, *r = &lv.r, *t = &lv.t;
  auto sweep = [&](bc::vector<double>& in, bc::vector<double>& o) {
    k_sweep_.set_args(n, A.row_ptr, A.col, A.val, lv.d, f, in, o);
    dev_.cl().launch(k_sweep_, n);
  };
  if (sweeps_ == 1) {
    k_first_.set_args(n, A.row_ptr, A.col, A.val, lv.d, f, *x, *r);
    dev_.cl().launch(k_first_, n);
  } else {
    k_scale_.set_args(n, lv.d, f, *x);
    dev_.cl().launch(k_scale_, n);
    for (int s = 1; s < sweeps_; ++s) {
      sweep(*x, *t);
      std::swap(x, t);
    }
    k_residual_.set_args(n, A.row_ptr, A.col, A.val, f, *x, *r);
    dev_.cl().launch(k_residual_, n);
  }
  Level& next = levels_[l + 1];
  k_spmv_.set_args(next.n, lv.R.row_ptr, lv.R.col, lv.R.val, *r, next.f);
  dev_.cl().launch(k_spmv_, next.n);
  vcycle(l + 1, next.f, next.out);
  k_prolong_.set_args(n, lv.P.row_ptr, lv.P.col, lv.P.val, next.out, *x, *t);
  dev_.cl().launch(k_prolong_, n);
  for (int s = 1; s < sweeps_; ++s) {
    sweep(*t, *r);
    std::swap(t, r);
  }
  sweep(*t, out);
}

}  // namespace vpm::detail
