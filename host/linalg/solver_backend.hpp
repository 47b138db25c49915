#pragma once
// Private: the two backends the solvers in solver.cpp are written over. Both expose the same
// small set of primitives (spmv, two-stage dots with a scalar update, fused vector updates) on
// a fixed set of work vectors; scalars live in the backend (on the device for OpenCL).
#include <array>
#include <boost/compute/container/vector.hpp>
#include <boost/compute/event.hpp>
#include <vector>

#include "core/device_cl.hpp"
#include "vpm/amg.hpp"
#include "vpm/device.hpp"
#include "vpm/sparse.hpp"

namespace vpm::detail {

class ClAmg;

enum Vec { VX, VB, VR, VP, VQ, VR0, VS, VT, VTMP, VZ, kNumVecs };  // VZ: z = M^-1 r (AMG-PCG)
constexpr int kMaxBlock = 3;  // columns of spmv_block (kernels/solver.cl)
// the scalar slots S_* and the operations OP_* that advance them (ks_finalize), shared with
// kernels/solver.cl
#include "kernels/krylov_scalars.clh"
using Op = int;  // an OP_* of krylov_scalars.clh
constexpr int kNumSlots = KS_SLOTS;

/// Plain loops on the host; matrices are CsrMatrix.
class HostBackend {
 public:
  explicit HostBackend(int n);
  int size() const { return n_; }
  /// `a`: the system matrix; `at`: its transpose (nullptr: a is symmetric). Kept by pointer.
  void set_matrix(const CsrMatrix* a, const CsrMatrix* at);
  void set_mask(const std::vector<char>& mask);  // length n, non-zero = fixed row
  /// d = 1/diag(A) (normal = false) or 1/column norms^2 of A (normal = true); 0 on fixed rows.
  void set_preconditioner(bool normal);
  void upload(Vec v, const double* data);
  void download(Vec v, double* data);
  void residual(Vec r, Vec b, Vec x);            // r = b - A x (fixed rows 0)
  void spmv(Vec y, Vec x, bool transpose);       // y = A x or A^T x (fixed rows 0)
  void spmv_scaled(Vec y, Vec x);                // y = A D x
  void dot(Vec a, Vec b, Op op);
  void dot2(Vec a, Vec b, Vec c, Vec e, Op op);
  void cg_init();      // p = D r; S[RZ] = r.Dr, S[RR] = r.r
  void cg_update_xr(); // x += alpha p; r -= alpha q; finalize(OP_CG_BETA)
  void cg_update_p();  // p = D r + beta p
  void bicg_s();       // s = r - alpha v   (v stored in VQ)
  void bicg_update();  // x += D(alpha p + omega s); r = s - omega t; finalize(OP_BI_BETA)
  void bicg_p();       // p = r + beta (p - omega v)
  // General preconditioner path of CG (used when a multigrid preconditioner is set; the
  // Jacobi CG above is untouched): z = M^-1 r, then x += alpha p, r -= alpha q; p = z + beta p.
  void set_amg(const AmgHierarchy* h) { amg_ = h; }  // nullptr: Jacobi
  bool has_amg() const { return amg_ != nullptr; }
  void precondition();  // VZ = M^-1 VR (one V-cycle)
  void pcg_update_xr();
  void pcg_update_p();
  void copy(Vec dst, Vec src);
  void request_rr(int ring);  // queue a read of S[RR] into ring slot 0/1
  double wait_rr(int ring);   // the value read
  double read_rr_now();       // blocking read of S[RR]
  int lookahead() const { return 1; }
  /// y = A x on each of the k backends (k <= kMaxBlock) that share one matrix and mask: the
  /// columns of a block solve (linalg/krylov_block.hpp); equal to k spmv calls bit for bit.
  static void spmv_block(HostBackend* const* columns, int k, Vec y, Vec x);

 private:
  void finalize(Op op, double p0, double p1);
  double* v(Vec i) { return vec_[i].data(); }
  int n_;
  const CsrMatrix* a_ = nullptr;
  const CsrMatrix* at_ = nullptr;
  const AmgHierarchy* amg_ = nullptr;
  std::vector<char> mask_;
  std::vector<double> d_;
  std::array<std::vector<double>, kNumVecs> vec_;
  std::array<double, kNumSlots> s_{};
  std::array<double, 2> ring_{};
};

/// OpenCL kernels of kernels/solver.cl; matrices are device CSR buffers.
class ClBackend {
 public:
  ClBackend(Device& device, int n);
  int size() const { return n_; }
  /// Device CSR buffers of A (and of A^T; nullptr: symmetric). Kept by pointer.
  void set_matrix(boost::compute::vector<int>* row_ptr, boost::compute::vector<int>* col,
                  boost::compute::vector<double>* val, boost::compute::vector<int>* t_row_ptr,
                  boost::compute::vector<int>* t_col, boost::compute::vector<double>* t_val);
  void set_mask(const std::vector<char>& mask);
  void set_preconditioner(bool normal);
  void upload(Vec v, const double* data);
  void download(Vec v, double* data);
  void residual(Vec r, Vec b, Vec x);
  void spmv(Vec y, Vec x, bool transpose);
  void spmv_scaled(Vec y, Vec x);
  void dot(Vec a, Vec b, Op op);
  void dot2(Vec a, Vec b, Vec c, Vec e, Op op);
  void cg_init();
  void cg_update_xr();
  void cg_update_p();
  void bicg_s();
  void bicg_update();
  void bicg_p();
  void set_amg(ClAmg* a) { amg_ = a; }  // nullptr: Jacobi
  bool has_amg() const { return amg_ != nullptr; }
  void precondition();
  void pcg_update_xr();
  void pcg_update_p();
  void copy(Vec dst, Vec src);
  void request_rr(int ring);
  double wait_rr(int ring);
  double read_rr_now();
  int lookahead() const { return 2; }
  /// As HostBackend::spmv_block: one kernel reads the matrix once for the k columns.
  static void spmv_block(ClBackend* const* columns, int k, Vec y, Vec x);

 private:
  void finalize(Op op);
  void set_csr_args(boost::compute::kernel& k, bool transpose);
  Device& dev_;
  int n_;
  size_t groups_;  // G: work items of the reductions
  boost::compute::vector<int>*row_ptr_ = nullptr, *col_ = nullptr, *t_row_ptr_ = nullptr,
                  *t_col_ = nullptr;
  boost::compute::vector<double>*val_ = nullptr, *t_val_ = nullptr;
  std::vector<boost::compute::vector<double>> vec_;
  boost::compute::vector<double> d_, partial_, s_;
  boost::compute::vector<char> mask_;
  boost::compute::kernel k_spmv_, k_spmv_t_, k_spmv_scaled_, k_residual_, k_inv_diag_,
      k_inv_rowsq_, k_dot_, k_dot2_, k_finalize_, k_cg_init_, k_cg_xr_, k_cg_p_, k_bicg_s_,
      k_bicg_update_, k_bicg_p_, k_pcg_xr_, k_pcg_p_, k_spmv_block_;
  ClAmg* amg_ = nullptr;
  std::array<double, 2> ring_{};
  std::array<boost::compute::event, 2> events_;
};

}  // namespace vpm::detail
