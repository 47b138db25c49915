// Polish step of the volume map on the device: the OpenCL backend's kernels of the polish's CGLS,
// whose loop is written once in host/map/polish_cgls.hpp (host backend: host/map/polish_host.cpp;
// a tet's row, kernels/polish_row.clh, and the iteration's scalars and tangent rule,
// kernels/polish_cgls.clh, are shared with it). min |A dx - b| with
//   A_(t, v) = vol_t grad phi_v / target_t   (v a corner of tet t),   b_t = 1 - vol_t / target_t,
// dx restricted per vertex (free / tangent to the sphere / zero / anchored). The iterations run
// without a host synchronisation: scalars live in S, reductions store partials (STORE_PARTIALS,
// kernels/common.clh) that polish_scalars combines.
//
// Reductions use a fixed grid of G work items (global size G) with a grid stride.

#define STRIDE_BEGIN(n) for (int i = get_global_id(0); i < (n); i += get_global_size(0))

#include "tet_geometry.clh"
#include "polish_row.clh"
#include "polish_cgls.clh"  // pl_scalars, pl_tangent, the slots P_* of S

// Per tet t: sg[12 t + 3 k + c] = vol_t / target_t * d lambda_k / d x_c, b[t], r[t] = b[t]
// (pl_row, as the host's HostPolishSystem).
__kernel void polish_setup(const int m, __global const int* tets, __global const real* x,
                           __global const real* target, __global real* sg, __global real* b,
                           __global real* r) {
  const int t = get_global_id(0);
  if (t >= m) return;
  __global const int* T = tets + 4 * t;
  real e1[3], e2[3], e3[3], g[12];
  tg_edges(x, T, e1, e2, e3);
  const real bt = pl_row(e1, e2, e3, target[t], g);
  for (int j = 0; j < 12; ++j) sg[12 * t + j] = g[j];
  b[t] = bt;
  r[t] = bt;
}

// q = A p; partial[g] = |q|^2 over this work item's tets
__kernel void polish_apply(const int m, __global const int* tets, __global const real* sg,
                           __global const real* p, __global real* q, __global real* partial) {
  REDUCE_SCRATCH;
  real acc = 0.0;
  STRIDE_BEGIN(m) {
    __global const real* g = sg + 12 * i;
    real s = 0.0;
    for (int k = 0; k < 4; ++k) {
      const int v = tets[4 * i + k];
      s += g[3 * k] * p[3 * v] + g[3 * k + 1] * p[3 * v + 1] + g[3 * k + 2] * p[3 * v + 2];
    }
    q[i] = s;
    acc += s * s;
  }
  STORE_PARTIALS(acc, 0.0, partial);
}

// (A^T y)_v: gather over the vertex's tet slots 4 t + k
inline void polish_gather(const int v, __global const int* inc_ptr, __global const int* inc_slot,
                          __global const real* sg, __global const real* y, real* sx, real* sy, real* sz) {
  real ax = 0.0, ay = 0.0, az = 0.0;
  for (int j = inc_ptr[v]; j < inc_ptr[v + 1]; ++j) {
    const int slot = inc_slot[j];
    const real w = y[slot >> 2];
    __global const real* g = sg + 3 * slot;
    ax += w * g[0];
    ay += w * g[1];
    az += w * g[2];
  }
  *sx = ax;
  *sy = ay;
  *sz = az;
}

// w = P A^T y; P: flags 0 free, 1 tangent to the sphere at x_v, 2 zero, 3 in an anchor group:
// anchor[v] = g and anchor_row[v] = its row there, the group's vertices
// group_vertex[group_ptr[g] ..) and its projector (k x k, row-major at
// group_matrix[group_offset[g]]): w_v = sum_j P[row][j] (A^T y)_(vertex j).
// recur 0 (the start, y = b): s = w, partial[g] = |s|^2, partial[G + g] = |y|^2 over this work
// item's range of the m tets' rows.
// recur 1 (an iteration, y = q = A p): s -= alpha w and dx += alpha p (alpha = S[P_ALPHA], the
// gradient's recurrence of host/map/polish_cgls.hpp), partial[g] = |s|^2, partial[G + g] = 0.
__kernel void polish_apply_t(const int n, const int m, __global const int* inc_ptr,
                             __global const int* inc_slot, __global const real* sg,
                             __global const real* y, __global const char* flags,
                             __global const real* x, __global real* s, __global real* partial,
                             __global const int* anchor, __global const int* anchor_row,
                             __global const int* group_ptr,
                             __global const int* group_vertex, __global const int* group_offset,
                             __global const real* group_matrix, const int recur,
                             __global const real* S, __global real* dx, __global const real* p) {
  REDUCE_SCRATCH;
  const real alpha = recur ? S[P_ALPHA] : 0.0;
  real acc = 0.0;
  STRIDE_BEGIN(n) {
    real sx = 0.0, sy = 0.0, sz = 0.0;
    if (flags[i] == 0 || flags[i] == 1) polish_gather(i, inc_ptr, inc_slot, sg, y, &sx, &sy, &sz);
    if (flags[i] == 1) {
      real u[3] = {sx, sy, sz};
      pl_tangent(x[3 * i], x[3 * i + 1], x[3 * i + 2], u);
      sx = u[0];
      sy = u[1];
      sz = u[2];
    } else if (flags[i] == 3) {
      const int g = anchor[i], row = anchor_row[i];
      const int b = group_ptr[g], k = group_ptr[g + 1] - b;
      __global const real* P = group_matrix + group_offset[g] + row * k;
      for (int j = 0; j < k; ++j) {
        real gx, gy, gz;
        polish_gather(group_vertex[b + j], inc_ptr, inc_slot, sg, y, &gx, &gy, &gz);
        sx += P[j] * gx;
        sy += P[j] * gy;
        sz += P[j] * gz;
      }
    }
    if (recur) {
      sx = s[3 * i] - alpha * sx;
      sy = s[3 * i + 1] - alpha * sy;
      sz = s[3 * i + 2] - alpha * sz;
      for (int c = 0; c < 3; ++c) dx[3 * i + c] += alpha * p[3 * i + c];
    }
    s[3 * i] = sx;
    s[3 * i + 1] = sy;
    s[3 * i + 2] = sz;
    acc += sx * sx + sy * sy + sz * sz;
  }
  real yy = 0.0;
  if (!recur) {
    STRIDE_BEGIN(m) yy += y[i] * y[i];
  }
  STORE_PARTIALS(acc, yy, partial);
}

// partial[G + g] = |b - q|^2 over this work item's range of the m tets' rows (the final residual,
// q = A dx), partial[g] = 0
__kernel void polish_residual(const int m, __global const real* b, __global const real* q,
                              __global real* partial) {
  REDUCE_SCRATCH;
  real rr = 0.0;
  STRIDE_BEGIN(m) {
    const real d = b[i] - q[i];
    rr += d * d;
  }
  STORE_PARTIALS(0.0, rr, partial);
}

__kernel void polish_scalars(const int G, const int op, __global const real* partial,
                             __global real* S) {
  REDUCE_SCRATCH;
  real p0, p1;
  COMBINE_PARTIALS(G, partial, op == P_OP_INIT || op == P_OP_RR, p0, p1);
  if (get_global_id(0) == 0) pl_scalars(op, p0, p1, S);
}

// p = s + beta p; with beta = 0 (the first call, or once stopped) p = s, never reading p
// (the buffer starts uninitialised: 0 * NaN would be NaN)
__kernel void polish_update_p(const int n3, __global const real* S, __global real* p,
                              __global const real* s) {
  const real beta = S[P_BETA];
  if (beta == 0.0) {
    STRIDE_BEGIN(n3) p[i] = s[i];
  } else {
    STRIDE_BEGIN(n3) p[i] = s[i] + beta * p[i];
  }
}
