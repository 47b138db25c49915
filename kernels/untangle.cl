// Untangling energy of Garanzha et al. 2021 (see include/vpm/untangle.hpp), one work item per
// active tet, and the per-vertex gather of the gradient (no atomics: CSR of contributions). The
// energy's formula is shared with the host (kernels/untangle_energy.clh).

#include "untangle_energy.clh"

// For active tet a (vertices tv[4a..4a+3], R^-1 row-major in rinv[9a..], weight w[a]):
//   e[a] = w f(J), d[a] = det J, and if want_grad: gt[12a + 3k + c] = dE/dx of corner k.
__kernel void untangle_tet(const int m, const real eps, const real theta, const int want_grad,
                           __global const int* tv, __global const real* rinv,
                           __global const real* w, __global const real* x, __global real* e,
                           __global real* d, __global real* gt) {
  const int a = get_global_id(0);
  if (a >= m) return;
  const real3 p0 = load3(x, tv[4 * a]);
  const real3 c0 = load3(x, tv[4 * a + 1]) - p0;
  const real3 c1 = load3(x, tv[4 * a + 2]) - p0;
  const real3 c2 = load3(x, tv[4 * a + 3]) - p0;
  __global const real* R = rinv + 9 * a;
  const real3 J0 = c0 * R[0] + c1 * R[3] + c2 * R[6];
  const real3 J1 = c0 * R[1] + c1 * R[4] + c2 * R[7];
  const real3 J2 = c0 * R[2] + c1 * R[5] + c2 * R[8];
  const real3 C0 = cross(J1, J2), C1 = cross(J2, J0), C2 = cross(J0, J1);
  const real det = dot(J0, C0);
  real k1, k2;
  const real f = ue_energy(det, dot(J0, J0) + dot(J1, J1) + dot(J2, J2), eps, theta, &k1, &k2);
  const real wa = w[a];
  e[a] = wa * f;
  d[a] = det;
  if (!want_grad) return;
  const real3 D0 = wa * (k1 * J0 + k2 * C0);
  const real3 D1 = wa * (k1 * J1 + k2 * C1);
  const real3 D2 = wa * (k1 * J2 + k2 * C2);
  const real3 G0 = D0 * R[0] + D1 * R[1] + D2 * R[2];
  const real3 G1 = D0 * R[3] + D1 * R[4] + D2 * R[5];
  const real3 G2 = D0 * R[6] + D1 * R[7] + D2 * R[8];
  const real3 g0 = -(G0 + G1 + G2);
  __global real* o = gt + 12 * a;
  o[0] = g0.x; o[1] = g0.y; o[2] = g0.z;
  o[3] = G0.x; o[4] = G0.y; o[5] = G0.z;
  o[6] = G1.x; o[7] = G1.y; o[8] = G1.z;
  o[9] = G2.x; o[10] = G2.y; o[11] = G2.z;
}

// g[3f + c] = sum of gt[slot[k] + c] over k in offset[f] .. offset[f+1] (free vertex f).
__kernel void untangle_gather(const int nfree, __global const int* offset,
                              __global const int* slot, __global const real* gt,
                              __global real* g) {
  const int f = get_global_id(0);
  if (f >= nfree) return;
  real3 s = (real3)(0.0, 0.0, 0.0);
  for (int k = offset[f]; k < offset[f + 1]; ++k) {
    const int b = slot[k];
    s += (real3)(gt[b], gt[b + 1], gt[b + 2]);
  }
  g[3 * f] = s.x;
  g[3 * f + 1] = s.y;
  g[3 * f + 2] = s.z;
}
