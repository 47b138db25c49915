#include "linalg/solver_backend.hpp"

#include "linalg/amg_device.hpp"
#include "core/device_cl.hpp"

#include <cmath>
#include <stdexcept>

namespace vpm::detail {

namespace bc = boost::compute;

// ---------------------------------------------------------------- host backend ------------

HostBackend::HostBackend(int n) : n_(n), mask_(n, 0), d_(n, 1.0) {
  for (auto& v : vec_) v.assign(n, 0.0);
}

void HostBackend::set_matrix(const CsrMatrix* a, const CsrMatrix* at) {
  a_ = a;
  at_ = at ? at : a;
}

void HostBackend::set_mask(const std::vector<char>& mask) { mask_ = mask; }

void HostBackend::set_preconditioner(bool normal) {
  const CsrMatrix& m = normal ? *at_ : *a_;
  for (int i = 0; i < n_; ++i) {
    double a = 0;
    for (int k = m.row_ptr[i]; k < m.row_ptr[i + 1]; ++k) {
      if (normal) {
        if (!mask_[m.col[k]]) a += m.val[k] * m.val[k];
      } else if (m.col[k] == i) {
        a = m.val[k];
      }
    }
    d_[i] = mask_[i] ? 0.0 : (a != 0.0 ? 1.0 / a : 1.0);
  }
}

void HostBackend::upload(Vec v, const double* data) { std::copy(data, data + n_, vec_[v].begin()); }
void HostBackend::download(Vec v, double* data) { std::copy(vec_[v].begin(), vec_[v].end(), data); }

void HostBackend::residual(Vec r, Vec b, Vec x) {
  const CsrMatrix& a = *a_;
  double *rr = v(r), *bb = v(b), *xx = v(x);
  for (int i = 0; i < n_; ++i) {
    double s = 0;
    if (!mask_[i]) {
      s = bb[i];
      for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) s -= a.val[k] * xx[a.col[k]];
    }
    rr[i] = s;
  }
}

void HostBackend::spmv(Vec y, Vec x, bool transpose) {
  const CsrMatrix& a = transpose ? *at_ : *a_;
  double *yy = v(y), *xx = v(x);
  for (int i = 0; i < n_; ++i) {
    double s = 0;
    if (!mask_[i])
      for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) s += a.val[k] * xx[a.col[k]];
    yy[i] = s;
  }
}

void HostBackend::spmv_scaled(Vec y, Vec x) {
  const CsrMatrix& a = *a_;
  double *yy = v(y), *xx = v(x);
  for (int i = 0; i < n_; ++i) {
    double s = 0;
    if (!mask_[i])
      for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) {
        const int j = a.col[k];
        s += a.val[k] * d_[j] * xx[j];
      }
    yy[i] = s;
  }
}

void HostBackend::finalize(Op op, double p0, double p1) { ks_finalize(op, p0, p1, s_.data()); }

void HostBackend::dot(Vec a, Vec b, Op op) {
  double s = 0;
  const double *aa = v(a), *bb = v(b);
  for (int i = 0; i < n_; ++i) s += aa[i] * bb[i];
  finalize(op, s, 0);
}

void HostBackend::dot2(Vec a, Vec b, Vec c, Vec e, Op op) {
  double s = 0, t = 0;
  const double *aa = v(a), *bb = v(b), *cc = v(c), *ee = v(e);
  for (int i = 0; i < n_; ++i) {
    s += aa[i] * bb[i];
    t += cc[i] * ee[i];
  }
  finalize(op, s, t);
}

void HostBackend::cg_init() {
  double s = 0, t = 0;
  double *r = v(VR), *p = v(VP);
  for (int i = 0; i < n_; ++i) {
    p[i] = d_[i] * r[i];
    s += r[i] * p[i];
    t += r[i] * r[i];
  }
  finalize(OP_CG_INIT, s, t);
}

void HostBackend::cg_update_xr() {
  const double alpha = s_[S_ALPHA];
  double *x = v(VX), *r = v(VR), *p = v(VP), *q = v(VQ);
  double s = 0, t = 0;
  for (int i = 0; i < n_; ++i) {
    x[i] += alpha * p[i];
    r[i] -= alpha * q[i];
    s += r[i] * d_[i] * r[i];
    t += r[i] * r[i];
  }
  finalize(OP_CG_BETA, s, t);
}

void HostBackend::cg_update_p() {
  const double beta = s_[S_BETA];
  double *r = v(VR), *p = v(VP);
  for (int i = 0; i < n_; ++i) p[i] = d_[i] * r[i] + beta * p[i];
}

void HostBackend::bicg_s() {
  const double alpha = s_[S_ALPHA];
  double *r = v(VR), *vv = v(VQ), *s = v(VS);
  for (int i = 0; i < n_; ++i) s[i] = r[i] - alpha * vv[i];
}

void HostBackend::bicg_update() {
  const double alpha = s_[S_ALPHA], omega = s_[S_OMEGA];
  double *x = v(VX), *r = v(VR), *s = v(VS), *t = v(VT), *p = v(VP), *r0 = v(VR0);
  double a = 0, b = 0;
  for (int i = 0; i < n_; ++i) {
    x[i] += d_[i] * (alpha * p[i] + omega * s[i]);
    r[i] = s[i] - omega * t[i];
    a += r0[i] * r[i];
    b += r[i] * r[i];
  }
  finalize(OP_BI_BETA, a, b);
}

void HostBackend::bicg_p() {
  const double beta = s_[S_BETA], omega = s_[S_OMEGA];
  double *r = v(VR), *vv = v(VQ), *p = v(VP);
  for (int i = 0; i < n_; ++i) p[i] = r[i] + beta * (p[i] - omega * vv[i]);
}

void HostBackend::precondition() { amg_->apply(v(VR), v(VZ)); }

void HostBackend::pcg_update_xr() {
  const double alpha = s_[S_ALPHA];
  double *x = v(VX), *r = v(VR), *p = v(VP), *q = v(VQ);
  for (int i = 0; i < n_; ++i) {
    x[i] += alpha * p[i];
    r[i] -= alpha * q[i];
  }
}

void HostBackend::pcg_update_p() {
  const double beta = s_[S_BETA];
  double *z = v(VZ), *p = v(VP);
  for (int i = 0; i < n_; ++i) p[i] = z[i] + beta * p[i];
}

void HostBackend::copy(Vec dst, Vec src) { vec_[dst] = vec_[src]; }
void HostBackend::request_rr(int ring) { ring_[ring] = s_[S_RR]; }
double HostBackend::wait_rr(int ring) { return ring_[ring]; }
double HostBackend::read_rr_now() { return s_[S_RR]; }

// ---------------------------------------------------------------- OpenCL backend ----------

ClBackend::ClBackend(Device& dev, int n)
    : dev_(dev), n_(n), d_(dev.cl().context), partial_(dev.cl().context), s_(dev.cl().context),
      mask_(dev.cl().context) {
  const size_t ls = dev.local_size();
  const unsigned cu = std::max(1u, dev.description().compute_units);
  const bool cpu = dev.description().kind == DeviceKind::cpu;
  // CPU (PoCL): a few work groups per core, each work item a contiguous chunk.
  // GPU: enough work items to fill the device, grid-stride.
  groups_ = cpu ? ls * std::max<size_t>(4, 2 * cu) : ls * std::max<size_t>(64, 4 * cu);
  const std::string opt = cpu ? "-DCHUNKED" : "";
  auto K = [&](const char* name) { return dev.cl().kernel("solver", name, opt); };
  k_spmv_ = K("spmv");
  k_spmv_t_ = K("spmv");
  k_spmv_scaled_ = K("spmv_scaled");
  k_residual_ = K("residual");
  k_inv_diag_ = K("inv_diagonal");
  k_inv_rowsq_ = K("inv_row_squares");
  k_dot_ = K("dot_partial");
  k_dot2_ = K("dot2_partial");
  k_finalize_ = K("finalize");
  k_cg_init_ = K("cg_init");
  k_cg_xr_ = K("cg_update_xr");
  k_cg_p_ = K("cg_update_p");
  k_bicg_s_ = K("bicg_s");
  k_bicg_update_ = K("bicg_update");
  k_bicg_p_ = K("bicg_p");
  k_pcg_xr_ = K("pcg_update_xr");
  k_pcg_p_ = K("pcg_update_p");
  k_spmv_block_ = K("spmv_block");
  const size_t nn = std::max(1, n);
  auto& q = dev.cl().queue;
  const std::vector<double> zeros(std::max(nn, 2 * groups_), 0.0);
  const std::vector<char> czeros(nn, 0);
  for (int i = 0; i < kNumVecs; ++i) vec_.emplace_back(zeros.begin(), zeros.begin() + nn, q);
  d_ = bc::vector<double>(zeros.begin(), zeros.begin() + nn, q);
  partial_ = bc::vector<double>(zeros.begin(), zeros.begin() + 2 * groups_, q);
  s_ = bc::vector<double>(zeros.begin(), zeros.begin() + kNumSlots, q);
  mask_ = bc::vector<char>(czeros.begin(), czeros.end(), q);

  k_dot_.set_arg(0, n);
  k_dot_.set_arg(3, partial_);
  k_dot2_.set_arg(0, n);
  k_dot2_.set_arg(5, partial_);
  k_finalize_.set_arg(0, static_cast<int>(dev.reduction_partials(groups_)));
  set_args_at(k_finalize_, 2, partial_, s_);
  k_cg_init_.set_args(n, vec_[VR], d_, vec_[VP], partial_);
  k_cg_xr_.set_args(n, s_, vec_[VX], vec_[VR], vec_[VP], vec_[VQ], d_, partial_);
  k_cg_p_.set_args(n, s_, vec_[VR], d_, vec_[VP]);
  k_bicg_s_.set_args(n, s_, vec_[VR], vec_[VQ], vec_[VS]);
  k_bicg_update_.set_args(n, s_, vec_[VX], vec_[VR], vec_[VS], vec_[VT], vec_[VP], d_, vec_[VR0],
                          partial_);
  k_bicg_p_.set_args(n, s_, vec_[VR], vec_[VQ], vec_[VP]);
  k_pcg_xr_.set_args(n, s_, vec_[VX], vec_[VR], vec_[VP], vec_[VQ]);
  k_pcg_p_.set_args(n, s_, vec_[VZ], vec_[VP]);
}

void ClBackend::set_csr_args(bc::kernel& k, bool transpose) {
  k.set_args(n_, transpose ? *t_row_ptr_ : *row_ptr_, transpose ? *t_col_ : *col_,
             transpose ? *t_val_ : *val_, mask_);
}

void ClBackend::set_matrix(bc::vector<int>* row_ptr, bc::vector<int>* col, bc::vector<double>* val,
                           bc::vector<int>* t_row_ptr, bc::vector<int>* t_col,
                           bc::vector<double>* t_val) {
  row_ptr_ = row_ptr;
  col_ = col;
  val_ = val;
  t_row_ptr_ = t_row_ptr ? t_row_ptr : row_ptr;
  t_col_ = t_row_ptr ? t_col : col;
  t_val_ = t_row_ptr ? t_val : val;
  set_csr_args(k_spmv_, false);
  set_csr_args(k_spmv_t_, true);
  set_csr_args(k_spmv_scaled_, false);
  set_csr_args(k_spmv_block_, false);
  k_spmv_scaled_.set_arg(5, d_);
  set_csr_args(k_residual_, false);
  set_csr_args(k_inv_diag_, false);
  k_inv_diag_.set_arg(5, d_);
  set_csr_args(k_inv_rowsq_, true);
  k_inv_rowsq_.set_arg(5, d_);
}

void ClBackend::set_mask(const std::vector<char>& mask) {
  if (n_ > 0) bc::copy(mask.begin(), mask.end(), mask_.begin(), dev_.cl().queue);
}

void ClBackend::set_preconditioner(bool normal) {
  dev_.cl().launch(normal ? k_inv_rowsq_ : k_inv_diag_, n_);
}

void ClBackend::upload(Vec v, const double* data) {
  if (n_ > 0) bc::copy(data, data + n_, vec_[v].begin(), dev_.cl().queue);
}
void ClBackend::download(Vec v, double* data) {
  if (n_ > 0) bc::copy(vec_[v].begin(), vec_[v].begin() + n_, data, dev_.cl().queue);
}

void ClBackend::residual(Vec r, Vec b, Vec x) {
  set_args_at(k_residual_, 5, vec_[b], vec_[x], vec_[r]);
  dev_.cl().launch(k_residual_, n_);
}

void ClBackend::spmv(Vec y, Vec x, bool transpose) {
  auto& k = transpose ? k_spmv_t_ : k_spmv_;
  set_args_at(k, 5, vec_[x], vec_[y]);
  dev_.cl().launch(k, n_);
}

void ClBackend::spmv_scaled(Vec y, Vec x) {
  set_args_at(k_spmv_scaled_, 6, vec_[x], vec_[y]);
  dev_.cl().launch(k_spmv_scaled_, n_);
}

void ClBackend::finalize(Op op) {
  k_finalize_.set_arg(1, static_cast<int>(op));
  dev_.cl().launch(k_finalize_, dev_.combine_items());
}

void ClBackend::dot(Vec a, Vec b, Op op) {
  set_args_at(k_dot_, 1, vec_[a], vec_[b]);
  dev_.cl().launch(k_dot_, groups_);
  finalize(op);
}

void ClBackend::dot2(Vec a, Vec b, Vec c, Vec e, Op op) {
  set_args_at(k_dot2_, 1, vec_[a], vec_[b], vec_[c], vec_[e]);
  dev_.cl().launch(k_dot2_, groups_);
  finalize(op);
}

void ClBackend::cg_init() {
  dev_.cl().launch(k_cg_init_, groups_);
  finalize(OP_CG_INIT);
}
void ClBackend::cg_update_xr() {
  dev_.cl().launch(k_cg_xr_, groups_);
  finalize(OP_CG_BETA);
}
void ClBackend::cg_update_p() { dev_.cl().launch(k_cg_p_, n_); }
void ClBackend::bicg_s() { dev_.cl().launch(k_bicg_s_, n_); }
void ClBackend::bicg_update() {
  dev_.cl().launch(k_bicg_update_, groups_);
  finalize(OP_BI_BETA);
}
void ClBackend::bicg_p() { dev_.cl().launch(k_bicg_p_, n_); }

void ClBackend::precondition() { amg_->apply(vec_[VR], vec_[VZ]); }
void ClBackend::pcg_update_xr() { dev_.cl().launch(k_pcg_xr_, n_); }
void ClBackend::pcg_update_p() { dev_.cl().launch(k_pcg_p_, n_); }

void ClBackend::copy(Vec dst, Vec src) {
  if (n_ > 0) bc::copy(vec_[src].begin(), vec_[src].end(), vec_[dst].begin(), dev_.cl().queue);
}

void ClBackend::request_rr(int ring) {
  events_[ring] = dev_.cl().queue.enqueue_read_buffer_async(s_.get_buffer(), S_RR * sizeof(double),
                                                         sizeof(double), &ring_[ring]);
}

double ClBackend::wait_rr(int ring) {
  events_[ring].wait();
  return ring_[ring];
}

double ClBackend::read_rr_now() {
  double r = 0;
  dev_.cl().queue.enqueue_read_buffer(s_.get_buffer(), S_RR * sizeof(double), sizeof(double), &r);
  return r;
}

}  // namespace vpm::detail
