// Geometry kernels: per-tet signed volumes and per-vertex dual volumes.
// Positions are n x 3 row-major doubles; tets are m x 4 row-major ints.

// vol[t] = det[b-a, c-a, d-a] / 6
__kernel void tet_volumes(const int m, __global const real* x, __global const int* tets,
                          __global real* vol) {
  const int t = get_global_id(0);
  if (t >= m) return;
  const real3 a = load3(x, tets[4 * t]);
  const real3 e1 = load3(x, tets[4 * t + 1]) - a;
  const real3 e2 = load3(x, tets[4 * t + 2]) - a;
  const real3 e3 = load3(x, tets[4 * t + 3]) - a;
  vol[t] = dot(e1, cross(e2, e3)) / 6.0;
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
