#include "linalg/amg_device.hpp"
#include "core/device_cl.hpp"
#include "linalg/amg_vcycle.hpp"

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

void ClAmg::apply(bc::vector<double>& f, bc::vector<double>& z) { amg_vcycle(*this, 0, &f, &z); }

void ClAmg::work(int l, Vec& x, Vec& r, Vec& t) {
  x = &levels_[l].x;
  r = &levels_[l].r;
  t = &levels_[l].t;
}

void ClAmg::coarse_vectors(int l, Vec& f, Vec& out) {
  f = &levels_[l].f;
  out = &levels_[l].out;
}

void ClAmg::first(int l, Vec f, Vec x, Vec r) {
  const Level& lv = levels_[l];
  k_first_.set_args(lv.n, lv.A.row_ptr, lv.A.col, lv.A.val, lv.d, *f, *x, *r);
  dev_.cl().launch(k_first_, lv.n);
}

void ClAmg::scale(int l, Vec f, Vec x) {
  const Level& lv = levels_[l];
  k_scale_.set_args(lv.n, lv.d, *f, *x);
  dev_.cl().launch(k_scale_, lv.n);
}

void ClAmg::sweep(int l, Vec f, Vec in, Vec o) {
  const Level& lv = levels_[l];
  k_sweep_.set_args(lv.n, lv.A.row_ptr, lv.A.col, lv.A.val, lv.d, *f, *in, *o);
  dev_.cl().launch(k_sweep_, lv.n);
}

void ClAmg::residual(int l, Vec f, Vec x, Vec r) {
  const Level& lv = levels_[l];
  k_residual_.set_args(lv.n, lv.A.row_ptr, lv.A.col, lv.A.val, *f, *x, *r);
  dev_.cl().launch(k_residual_, lv.n);
}

void ClAmg::restrict_to(int l, Vec r, Vec fc) {
  const Csr& R = levels_[l].R;
  const int nc = levels_[l + 1].n;
  k_spmv_.set_args(nc, R.row_ptr, R.col, R.val, *r, *fc);
  dev_.cl().launch(k_spmv_, nc);
}

void ClAmg::prolong(int l, Vec xc, Vec x, Vec t) {
  const Level& lv = levels_[l];
  k_prolong_.set_args(lv.n, lv.P.row_ptr, lv.P.col, lv.P.val, *xc, *x, *t);
  dev_.cl().launch(k_prolong_, lv.n);
}

void ClAmg::coarse(int l, Vec f, Vec out) {
  const int n = levels_[l].n;
  k_dense_.set_args(n, coarse_inv_, *f, *out);
  dev_.cl().launch(k_dense_, n);
}

}  // namespace vpm::detail
