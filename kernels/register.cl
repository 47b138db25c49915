// Registration kernels: evaluation of divergence-free RBF fields (include/vpm/rbf.hpp) and
// RK4 advection of points through a sequence of such fields (include/vpm/registration.hpp), or
// through the sphere registration's fields (kind 2, host/register/sphere_field.hpp).
// Points, centres and coefficients are n x 3 row-major doubles. One work item per point,
// looping over the centres (the dominant cost: centres x points x 4 stages x steps).

#include "rbf_kernel.clh"  // rk_free, rk_tangent: the kernels applied to a coefficient, as the host

// out[i] = u(x[i]) for the nc centres of one field.
__kernel void eval_field(const int n, __global const real* x, const int nc,
                         __global const real* centres, __global const real* coefs, const real l,
                         const int tangent, __global real* out) {
  const int i = get_global_id(0);
  if (i >= n) return;
  const real p[3] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
  real u[3] = {0.0, 0.0, 0.0};
  for (int j = 0; j < nc; ++j) {
    const real y[3] = {centres[3 * j], centres[3 * j + 1], centres[3 * j + 2]};
    const real c[3] = {coefs[3 * j], coefs[3 * j + 1], coefs[3 * j + 2]};
    real t[3];
    if (tangent) {
      rk_tangent(p, y, c, l, t);
    } else {
      const real r[3] = {p[0] - y[0], p[1] - y[1], p[2] - y[2]};
      rk_free(r, c, l, t);
    }
    for (int k = 0; k < 3; ++k) u[k] += t[k];
  }
  for (int k = 0; k < 3; ++k) out[3 * i + k] = u[k];
}

#include "rbf_advect.clh"  // the grid of centres, the cut, RK4 of LANES points

// Integrates dx/dt = u(x, t) over `steps` RK4 steps of length dt for nv = padded n / LANES
// vectors of points (structure of arrays xs, ys, zs, padded to a multiple of LANES), through the
// fields packed as rbf_advect.clh describes. The whole path of a point stays in registers: one
// launch for the whole advection.
__kernel void rk4_advect_soa(const int nv, __global real* xs, __global real* ys, __global real* zs,
                             const int steps, const real dt, __global const int* slot,
                             __global const int* cells, const real o0, const real o1, const real o2,
                             const real side, const int g, const real reach,
                             __global const real* centres, __global const real* coefs,
                             const real l, const real cut, const int kind) {
  const int i = get_global_id(0);
  if (i >= nv) return;
  const CentreGrid grid = {o0, o1, o2, side, g};
  vreal p0 = VLOAD(i, xs), p1 = VLOAD(i, ys), p2 = VLOAD(i, zs);
  rk4_points(&p0, &p1, &p2, steps, dt, slot, cells, grid, reach, centres, coefs, l, cut, kind);
  VSTORE(p0, i, xs);
  VSTORE(p1, i, ys);
  VSTORE(p2, i, zs);
}
