// The primitives of the AMG preconditioner's V-cycle on the device (the cycle itself is written
// once in host/linalg/amg_vcycle.hpp; ClAmg in host/linalg/amg_device.cpp enqueues these, the
// host's backend in host/linalg/amg.cpp runs the same loops). CSR one row per work item, no
// masks: fixed rows have d = 0 and empty rows in P, so they stay 0.

// Pre-smoothing from zero with the residual fused in: x = d f; r = f - A (d f).
__kernel void amg_first(const int n, __global const int* row_ptr, __global const int* col,
                        __global const real* val, __global const real* d,
                        __global const real* f, __global real* x, __global real* r) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real s = f[i];
  const int e = row_ptr[i + 1];
  for (int k = row_ptr[i]; k < e; ++k) {
    const int j = col[k];
    s -= val[k] * (d[j] * f[j]);
  }
  x[i] = d[i] * f[i];
  r[i] = s;
}

// x = d f
__kernel void amg_scale(const int n, __global const real* d, __global const real* f,
                        __global real* x) {
  const int i = get_global_id(0);
  if (i >= n) return;
  x[i] = d[i] * f[i];
}

// One smoothing sweep: out = in + d (f - A in)
__kernel void amg_sweep(const int n, __global const int* row_ptr, __global const int* col,
                        __global const real* val, __global const real* d,
                        __global const real* f, __global const real* in, __global real* out) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real s = f[i];
  const int e = row_ptr[i + 1];
  for (int k = row_ptr[i]; k < e; ++k) s -= val[k] * in[col[k]];
  out[i] = in[i] + d[i] * s;
}

// r = f - A x
__kernel void amg_residual(const int n, __global const int* row_ptr, __global const int* col,
                           __global const real* val, __global const real* f,
                           __global const real* x, __global real* r) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real s = f[i];
  const int e = row_ptr[i + 1];
  for (int k = row_ptr[i]; k < e; ++k) s -= val[k] * x[col[k]];
  r[i] = s;
}

// y = M x (restriction with R)
__kernel void amg_spmv(const int n, __global const int* row_ptr, __global const int* col,
                       __global const real* val, __global const real* x, __global real* y) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real s = 0.0;
  const int e = row_ptr[i + 1];
  for (int k = row_ptr[i]; k < e; ++k) s += val[k] * x[col[k]];
  y[i] = s;
}

// Coarse-grid correction: t = x + P xc
__kernel void amg_prolong(const int n, __global const int* row_ptr, __global const int* col,
                          __global const real* val, __global const real* xc,
                          __global const real* x, __global real* t) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real s = x[i];
  const int e = row_ptr[i + 1];
  for (int k = row_ptr[i]; k < e; ++k) s += val[k] * xc[col[k]];
  t[i] = s;
}

// Coarsest level: x = M f with the dense row-major n x n (pseudo-)inverse M
__kernel void amg_dense(const int n, __global const real* m, __global const real* f,
                        __global real* x) {
  const int i = get_global_id(0);
  if (i >= n) return;
  __global const real* row = m + (size_t)i * n;
  real s = 0.0;
  for (int j = 0; j < n; ++j) s += row[j] * f[j];
  x[i] = s;
}
