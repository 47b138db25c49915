// Geometry kernels: per-tet signed volumes and per-vertex dual volumes.
// Positions are n x 3 row-major doubles; tets are m x 4 row-major ints.

#include "tet_geometry.clh"

// vol[t] = det[b-a, c-a, d-a] / 6 (tg_volume, as the host's tet_volumes)
__kernel void tet_volumes(const int m, __global const real* x, __global const int* tets,
                          __global real* vol) {
  const int t = get_global_id(0);
  if (t >= m) return;
  __global const int* T = tets + 4 * t;
  real e1[3], e2[3], e3[3];
  tg_edges(x, T, e1, e2, e3);
  vol[t] = tg_volume(e1, e2, e3);
}

// dual[v] = sum over tets t touching v of vol[t] / 4 (gather through the CSR incidence,
// no atomics: one work item per vertex).
__kernel void dual_volumes(const int n, __global const int* offset, __global const int* tet_of,
                           __global const real* vol, __global real* dual) {
  const int v = get_global_id(0);
  if (v >= n) return;
  real s = 0.0;
  for (int k = offset[v]; k < offset[v + 1]; ++k) s += vol[tet_of[k]];
  dual[v] = 0.25 * s;
}
