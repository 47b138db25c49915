// Cotangent Laplacian values for moving vertices on a fixed CSR pattern (see vpm/laplacian.hpp).
// Positions n x 3 row-major; tets m x 4 row-major. The arithmetic is written once for host and
// device in cotan_laplacian.clh (host/linalg/laplacian.cpp runs the same functions).

#include "tet_geometry.clh"
#include "cotan_laplacian.clh"

// Per tet: the six off-diagonal stiffness entries and the signed volume (cl_tet_weights).
__kernel void tet_weights(const int m, __global const real* x, __global const int* tets,
                          __global real* w, __global real* vol) {
  const int t = get_global_id(0);
  if (t >= m) return;
  real e1[3], e2[3], e3[3];
  tg_edges(x, tets + 4 * t, e1, e2, e3);
  vol[t] = cl_tet_weights(e1, e2, e3, w + 6 * t);
}

// One work item per row (cl_assemble_row): no atomics, only work item i writes row i; also the
// lumped mass (a quarter of the incident volumes).
__kernel void assemble_rows(const int n, __global const int* row_ptr,
                            __global const int* inc_offset, __global const int* inc_tet,
                            __global const int* tets, __global const int* slot,
                            __global const int* diag, __global const real* w,
                            __global const real* vol, __global real* val, __global real* mass) {
  const int i = get_global_id(0);
  if (i >= n) return;
  cl_assemble_row(i, row_ptr, inc_offset, inc_tet, tets, slot, diag, w, vol, val, mass);
}
