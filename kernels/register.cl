// Registration kernels: evaluation of divergence-free RBF fields (include/vpm/rbf.hpp) and
// RK4 advection of points through a sequence of such fields (include/vpm/registration.hpp).
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

// ---- SIMD variant: each work item advects LANES points held in vector registers -------------
// Positions are structure-of-arrays (xs, ys, zs), padded to a multiple of LANES. LANES is
// injected with -DLANES=8 for CPU devices (PoCL maps double8 onto AVX registers and its vector
// exp) and -DLANES=1 elsewhere.
#ifndef LANES
#define LANES 1
#endif
#if LANES == 1
typedef real vreal;
#define VLOAD(i, p) ((p)[i])
#define VSTORE(v, i, p) ((p)[i] = (v))
#else
#define VCAT_(a, b) a##b
#define VCAT(a, b) VCAT_(a, b)
typedef VCAT(double, LANES) vreal;
#define VLOAD(i, p) VCAT(vload, LANES)(i, p)
#define VSTORE(v, i, p) VCAT(vstore, LANES)(v, i, p)
#endif

// (u0, u1, u2) += sum over centres [b, e) of K(x, y_j) c_j, with the per-centre terms regrouped:
//   free:    psi [(4l - 4l^2 r2) c + 4l^2 (r.c) r]
//   tangent: psi [(tr - 2l px py) c - (4 x.c + 4l px r.c) y + (4l py x.c + 4l^2 px py r.c) r]
// A centre whose Gaussian is below exp(-cut) at every lane's point is skipped: with the host's
// cut of 32 its terms are at most about 32 exp(-32) = 4e-13 of a near centre's, far below what
// the integration resolves.
#if LANES == 1
#define ALL_FAR(e, cut) ((e) > (cut))
#else
#define ALL_FAR(e, cut) all((e) > (cut))
#endif

inline void field_range_v(const vreal x0, const vreal x1, const vreal x2, const int b, const int e,
                          __global const real* centres, __global const real* coefs, const real l,
                          const real cut, const int tangent, vreal* u0, vreal* u1, vreal* u2) {
  vreal a0 = 0, a1 = 0, a2 = 0;
  const real l2 = l * l;
  if (tangent) {
    const vreal px = 1.0 - (x0 * x0 + x1 * x1 + x2 * x2);
    for (int j = b; j < e; ++j) {
      const real y0 = centres[3 * j], y1 = centres[3 * j + 1], y2 = centres[3 * j + 2];
      const real c0 = coefs[3 * j], c1 = coefs[3 * j + 1], c2 = coefs[3 * j + 2];
      const real py = 1.0 - (y0 * y0 + y1 * y1 + y2 * y2);
      const vreal r0 = x0 - y0, r1 = x1 - y1, r2 = x2 - y2;
      const vreal rr = r0 * r0 + r1 * r1 + r2 * r2;
      if (ALL_FAR(l * rr, cut)) continue;
      const vreal psi = exp(-l * rr);
      const vreal xc = x0 * c0 + x1 * c1 + x2 * c2;
      const vreal rc = r0 * c0 + r1 * c1 + r2 * c2;
      const vreal xy = x0 * y0 + x1 * y1 + x2 * y2;
      const vreal xr = x0 * r0 + x1 * r1 + x2 * r2;
      const vreal ry = r0 * y0 + r1 * y1 + r2 * y2;
      const vreal pp = px * py;
      const vreal tr = 4.0 * xy - (4.0 * l * py) * xr + (4.0 * l) * px * ry - pp * (4.0 * l2 * rr - 6.0 * l);
      const vreal fc = psi * (tr - (2.0 * l) * pp);
      const vreal fy = psi * (4.0 * xc + (4.0 * l) * px * rc);
      const vreal fr = psi * ((4.0 * l * py) * xc + (4.0 * l2) * pp * rc);
      a0 += fc * c0 - fy * y0 + fr * r0;
      a1 += fc * c1 - fy * y1 + fr * r1;
      a2 += fc * c2 - fy * y2 + fr * r2;
    }
  } else {
    for (int j = b; j < e; ++j) {
      const real c0 = coefs[3 * j], c1 = coefs[3 * j + 1], c2 = coefs[3 * j + 2];
      const vreal r0 = x0 - centres[3 * j], r1 = x1 - centres[3 * j + 1], r2 = x2 - centres[3 * j + 2];
      const vreal rr = r0 * r0 + r1 * r1 + r2 * r2;
      if (ALL_FAR(l * rr, cut)) continue;
      const vreal psi = exp(-l * rr);
      const vreal fc = psi * (4.0 * l - (4.0 * l2) * rr);
      const vreal fr = psi * (4.0 * l2) * (r0 * c0 + r1 * c1 + r2 * c2);
      a0 += fc * c0 + fr * r0;
      a1 += fc * c1 + fr * r1;
      a2 += fc * c2 + fr * r2;
    }
  }
  *u0 += a0;
  *u1 += a1;
  *u2 += a2;
}

// The smallest and largest of a vector's lanes.
#if LANES == 1
inline real lane_min(const vreal v) { return v; }
inline real lane_max(const vreal v) { return v; }
#elif LANES == 8
inline real lane_min(const vreal v) {
  const double4 a = fmin(v.lo, v.hi);
  const double2 b = fmin(a.lo, a.hi);
  return fmin(b.lo, b.hi);
}
inline real lane_max(const vreal v) {
  const double4 a = fmax(v.lo, v.hi);
  const double2 b = fmax(a.lo, a.hi);
  return fmax(b.lo, b.hi);
}
#else
#error "LANES must be 1 or 8"
#endif

// The cells of the centres' grid (g per axis from `origin`, side `side`) that a coordinate
// range [lo, hi] meets, clamped to the grid as the host clamps the centres into it.
inline int2 cell_span(const real lo, const real hi, const real origin, const real side, const int g) {
  const int a = (int)floor((lo - origin) / side), b = (int)floor((hi - origin) / side);
  return (int2)(clamp(a, 0, g - 1), clamp(b, 0, g - 1));
}

// One field's grid of centres: the centres sorted by cell (x fastest), cells[c] .. cells[c + 1]
// the range of cell c (g^3 + 1 entries), so a row of cells along x is one contiguous range.
typedef struct {
  real o0, o1, o2, side;
  int g;
} CentreGrid;

// (u0, u1, u2) = the field at the lanes' points: only the centres in the cells within `reach` of
// the lanes' bounding box, where reach^2 l > cut: every centre left out is one field_range_v
// would skip, so the sum has the same terms as over all centres (in cell order).
inline void field_v(const vreal x0, const vreal x1, const vreal x2, __global const int* cells,
                    const CentreGrid grid, const real reach, __global const real* centres,
                    __global const real* coefs, const real l, const real cut, const int tangent, vreal* u0,
                    vreal* u1, vreal* u2) {
  *u0 = 0;
  *u1 = 0;
  *u2 = 0;
  const int g = grid.g;
  const int2 sx = cell_span(lane_min(x0) - reach, lane_max(x0) + reach, grid.o0, grid.side, g);
  const int2 sy = cell_span(lane_min(x1) - reach, lane_max(x1) + reach, grid.o1, grid.side, g);
  const int2 sz = cell_span(lane_min(x2) - reach, lane_max(x2) + reach, grid.o2, grid.side, g);
  for (int cz = sz.x; cz <= sz.y; ++cz)
    for (int cy = sy.x; cy <= sy.y; ++cy) {
      const int row = (cz * g + cy) * g;
      field_range_v(x0, x1, x2, cells[row + sx.x], cells[row + sx.y + 1], centres, coefs, l, cut, tangent, u0, u1,
                    u2);
    }
}

// Integrates dx/dt = u(x, t) over `steps` RK4 steps of length dt for nv = padded n / LANES
// vectors of points. Field slot s (time s * dt / 2) is field slot[s], whose cell table starts at
// cells + slot[s] * (g^3 + 1); step k uses slots 2k, 2k+1, 2k+2. The whole path of a point stays
// in registers: one launch for the whole advection.
__kernel void rk4_advect_soa(const int nv, __global real* xs, __global real* ys, __global real* zs,
                             const int steps, const real dt, __global const int* slot,
                             __global const int* cells, const real o0, const real o1, const real o2,
                             const real side, const int g, const real reach,
                             __global const real* centres, __global const real* coefs,
                             const real l, const real cut, const int tangent) {
  const int i = get_global_id(0);
  if (i >= nv) return;
  const CentreGrid grid = {o0, o1, o2, side, g};
  const int table = g * g * g + 1;
  vreal p0 = VLOAD(i, xs), p1 = VLOAD(i, ys), p2 = VLOAD(i, zs);
  const real h = 0.5 * dt;
  for (int k = 0; k < steps; ++k) {
    __global const int* c1 = cells + slot[2 * k] * table;
    __global const int* c2 = cells + slot[2 * k + 1] * table;
    __global const int* c4 = cells + slot[2 * k + 2] * table;
    vreal k10, k11, k12, k20, k21, k22, k30, k31, k32, k40, k41, k42;
    field_v(p0, p1, p2, c1, grid, reach, centres, coefs, l, cut, tangent, &k10, &k11, &k12);
    field_v(p0 + h * k10, p1 + h * k11, p2 + h * k12, c2, grid, reach, centres, coefs, l, cut, tangent, &k20, &k21,
            &k22);
    field_v(p0 + h * k20, p1 + h * k21, p2 + h * k22, c2, grid, reach, centres, coefs, l, cut, tangent, &k30, &k31,
            &k32);
    field_v(p0 + dt * k30, p1 + dt * k31, p2 + dt * k32, c4, grid, reach, centres, coefs, l, cut, tangent, &k40, &k41,
            &k42);
    const real w = dt / 6.0;
    p0 += w * (k10 + 2.0 * k20 + 2.0 * k30 + k40);
    p1 += w * (k11 + 2.0 * k21 + 2.0 * k31 + k41);
    p2 += w * (k12 + 2.0 * k22 + 2.0 * k32 + k42);
  }
  VSTORE(p0, i, xs);
  VSTORE(p1, i, ys);
  VSTORE(p2, i, zs);
}
