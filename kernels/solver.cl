// Sparse solver primitives (vpm/solver.hpp): CSR spmv one row per work item, fused CG and
// BiCGSTAB vector updates, and two-stage dot products. Scalars (alpha, beta, ...) stay on the
// device in a small array S; the host reads one residual per iteration.
//
// Reductions run on a fixed grid of G work items (a multiple of the local size) and store
// partial sums with STORE_PARTIALS; "finalize" combines them (kernels/common.clh: per work item
// on CPUs, per work group on GPUs). With -DCHUNKED (CPU devices) each work item sums a
// contiguous chunk, else a grid stride (coalesced on GPUs).

#include "krylov_scalars.clh"  // the slots S_* of S, the operations OP_*, ks_finalize (shared with the host)

#ifdef CHUNKED
#define RANGE_BEGIN(n)                                                   \
  const int g_ = get_global_id(0), G_ = get_global_size(0);              \
  const int chunk_ = (((n) + G_ - 1) / G_ + 7) & ~7;                     \
  const int b_ = min((n), g_ * chunk_), e_ = min((n), b_ + chunk_);      \
  for (int i = b_; i < e_; ++i)
#else
#define RANGE_BEGIN(n) \
  for (int i = get_global_id(0); i < (n); i += get_global_size(0))
#endif

// y = A x on rows that are not masked; masked rows give 0.
__kernel void spmv(const int n, __global const int* row_ptr, __global const int* col,
                   __global const real* val, __global const char* mask,
                   __global const real* x, __global real* y) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real s = 0.0;
  if (!mask[i]) {
    const int e = row_ptr[i + 1];
    for (int k = row_ptr[i]; k < e; ++k) s += val[k] * x[col[k]];
  }
  y[i] = s;
}

// spmv for up to three vectors at once (the columns of a block solve): the matrix is read once;
// each y_c is summed in the same order as spmv, so it equals spmv's bit for bit. Columns c >= k
// are not touched (their arguments may repeat column 0's).
__kernel void spmv_block(const int n, __global const int* row_ptr, __global const int* col,
                         __global const real* val, __global const char* mask, const int k,
                         __global const real* x0, __global const real* x1, __global const real* x2,
                         __global real* y0, __global real* y1, __global real* y2) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real s0 = 0.0, s1 = 0.0, s2 = 0.0;
  if (!mask[i]) {
    const int e = row_ptr[i + 1];
    for (int q = row_ptr[i]; q < e; ++q) {
      const real a = val[q];
      const int j = col[q];
      s0 += a * x0[j];
      if (k > 1) s1 += a * x1[j];
      if (k > 2) s2 += a * x2[j];
    }
  }
  y0[i] = s0;
  if (k > 1) y1[i] = s1;
  if (k > 2) y2[i] = s2;
}

// y = A diag(d) x (right Jacobi preconditioning fused into the product).
__kernel void spmv_scaled(const int n, __global const int* row_ptr, __global const int* col,
                          __global const real* val, __global const char* mask,
                          __global const real* d, __global const real* x, __global real* y) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real s = 0.0;
  if (!mask[i]) {
    const int e = row_ptr[i + 1];
    for (int k = row_ptr[i]; k < e; ++k) {
      const int j = col[k];
      s += val[k] * d[j] * x[j];
    }
  }
  y[i] = s;
}

// r = b - A x on unmasked rows, 0 on masked rows.
__kernel void residual(const int n, __global const int* row_ptr, __global const int* col,
                       __global const real* val, __global const char* mask,
                       __global const real* b, __global const real* x, __global real* r) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real s = 0.0;
  if (!mask[i]) {
    s = b[i];
    const int e = row_ptr[i + 1];
    for (int k = row_ptr[i]; k < e; ++k) s -= val[k] * x[col[k]];
  }
  r[i] = s;
}

// Jacobi: d_i = 1 / A_ii (0 on masked rows, 1 where the diagonal is 0).
__kernel void inv_diagonal(const int n, __global const int* row_ptr, __global const int* col,
                           __global const real* val, __global const char* mask,
                           __global real* d) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real a = 0.0;
  for (int k = row_ptr[i]; k < row_ptr[i + 1]; ++k)
    if (col[k] == i) a = val[k];
  d[i] = mask[i] ? 0.0 : (a != 0.0 ? 1.0 / a : 1.0);
}

// Jacobi for the normal equations: d_i = 1 / sum_{j unmasked} B_ij^2 where B is the transpose
// of the system matrix (so this is the column norm of A), 0 on masked rows.
__kernel void inv_row_squares(const int n, __global const int* row_ptr, __global const int* col,
                              __global const real* val, __global const char* mask,
                              __global real* d) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real a = 0.0;
  for (int k = row_ptr[i]; k < row_ptr[i + 1]; ++k)
    if (!mask[col[k]]) a += val[k] * val[k];
  d[i] = mask[i] ? 0.0 : (a != 0.0 ? 1.0 / a : 1.0);
}

// partial[g] = a . b over this work item's range
__kernel void dot_partial(const int n, __global const real* a, __global const real* b,
                          __global real* partial) {
  REDUCE_SCRATCH;
  real s = 0.0;
  RANGE_BEGIN(n) s += a[i] * b[i];
  STORE_PARTIALS(s, 0.0, partial);
}

// partial[g] = a . b, partial[G + g] = c . e
__kernel void dot2_partial(const int n, __global const real* a, __global const real* b,
                           __global const real* c, __global const real* e,
                           __global real* partial) {
  REDUCE_SCRATCH;
  real s = 0.0, t = 0.0;
  RANGE_BEGIN(n) {
    s += a[i] * b[i];
    t += c[i] * e[i];
  }
  STORE_PARTIALS(s, t, partial);
}

// Combines the partial sums (one work group, or one item on CPUs) and updates the scalars.
__kernel void finalize(const int G, const int op, __global const real* partial,
                       __global real* S) {
  REDUCE_SCRATCH;
  real p0, p1;
  COMBINE_PARTIALS(G, partial, ks_uses_p1(op), p0, p1);
  if (get_global_id(0) == 0) ks_finalize(op, p0, p1, S);
}

// CG start: p = d r; partials r . p and r . r
__kernel void cg_init(const int n, __global const real* r, __global const real* d,
                      __global real* p, __global real* partial) {
  REDUCE_SCRATCH;
  real s = 0.0, t = 0.0;
  RANGE_BEGIN(n) {
    const real ri = r[i], pi = d[i] * ri;
    p[i] = pi;
    s += ri * pi;
    t += ri * ri;
  }
  STORE_PARTIALS(s, t, partial);
}

// CG: x += alpha p; r -= alpha q; partials r . d r and r . r
__kernel void cg_update_xr(const int n, __global const real* S, __global real* x,
                           __global real* r, __global const real* p, __global const real* q,
                           __global const real* d, __global real* partial) {
  REDUCE_SCRATCH;
  const real alpha = S[S_ALPHA];
  real s = 0.0, t = 0.0;
  RANGE_BEGIN(n) {
    x[i] += alpha * p[i];
    const real ri = r[i] - alpha * q[i];
    r[i] = ri;
    s += ri * d[i] * ri;
    t += ri * ri;
  }
  STORE_PARTIALS(s, t, partial);
}

// CG: p = d r + beta p
__kernel void cg_update_p(const int n, __global const real* S, __global const real* r,
                          __global const real* d, __global real* p) {
  const int i = get_global_id(0);
  if (i >= n) return;
  p[i] = d[i] * r[i] + S[S_BETA] * p[i];
}

// BiCGSTAB: s = r - alpha v
__kernel void bicg_s(const int n, __global const real* S, __global const real* r,
                     __global const real* v, __global real* s) {
  const int i = get_global_id(0);
  if (i >= n) return;
  s[i] = r[i] - S[S_ALPHA] * v[i];
}

// BiCGSTAB: x += d (alpha p + omega s); r = s - omega t; partials r0 . r and r . r
__kernel void bicg_update(const int n, __global const real* S, __global real* x,
                          __global real* r, __global const real* s, __global const real* t,
                          __global const real* p, __global const real* d,
                          __global const real* r0, __global real* partial) {
  REDUCE_SCRATCH;
  const real alpha = S[S_ALPHA], omega = S[S_OMEGA];
  real a = 0.0, b = 0.0;
  RANGE_BEGIN(n) {
    x[i] += d[i] * (alpha * p[i] + omega * s[i]);
    const real ri = s[i] - omega * t[i];
    r[i] = ri;
    a += r0[i] * ri;
    b += ri * ri;
  }
  STORE_PARTIALS(a, b, partial);
}

// BiCGSTAB: p = r + beta (p - omega v)
__kernel void bicg_p(const int n, __global const real* S, __global const real* r,
                     __global const real* v, __global real* p) {
  const int i = get_global_id(0);
  if (i >= n) return;
  p[i] = r[i] + S[S_BETA] * (p[i] - S[S_OMEGA] * v[i]);
}

// PCG (general preconditioner): x += alpha p; r -= alpha q
__kernel void pcg_update_xr(const int n, __global const real* S, __global real* x,
                            __global real* r, __global const real* p, __global const real* q) {
  const int i = get_global_id(0);
  if (i >= n) return;
  const real alpha = S[S_ALPHA];
  x[i] += alpha * p[i];
  r[i] -= alpha * q[i];
}

// PCG: p = z + beta p
__kernel void pcg_update_p(const int n, __global const real* S, __global const real* z,
                           __global real* p) {
  const int i = get_global_id(0);
  if (i >= n) return;
  p[i] = z[i] + S[S_BETA] * p[i];
}

// triad (bandwidth reference for benchmarks): a = b + s c
__kernel void triad(const int n, const real s, __global real* a, __global const real* b,
                    __global const real* c) {
  const int i = get_global_id(0);
  if (i >= n) return;
  a[i] = b[i] + s * c[i];
}
