// Registration kernels: evaluation of divergence-free RBF fields (include/vpm/rbf.hpp) and
// RK4 advection of points through a sequence of such fields (include/vpm/registration.hpp).
// Points, centres and coefficients are n x 3 row-major doubles. One work item per point,
// looping over the centres (the dominant cost: centres x points x 4 stages x steps).

inline real3 reg_load3(__global const real* x, int i) {
  return (real3)(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
}

// Free kernel: Phi(r) c = [(4l - 4l^2 |r|^2) c + 4l^2 r (r.c)] exp(-l |r|^2)
inline real3 apply_free(const real3 r, const real3 c, const real l) {
  const real r2 = dot(r, r);
  const real psi = exp(-l * r2);
  return psi * ((4.0 * l - 4.0 * l * l * r2) * c + (4.0 * l * l * dot(r, c)) * r);
}

// Tangent kernel: K(x, y) c = psi (tr(H) c - H^T c), phi(x) = 1 - |x|^2 (see rbf.hpp).
inline real3 apply_tangent(const real3 x, const real3 y, const real3 c, const real l) {
  const real3 r = x - y;
  const real r2 = dot(r, r);
  const real psi = exp(-l * r2);
  const real px = 1.0 - dot(x, x), py = 1.0 - dot(y, y);
  const real xc = dot(x, c), rc = dot(r, c);
  const real tr = 4.0 * dot(x, y) - 4.0 * l * py * dot(x, r) + 4.0 * l * px * dot(r, y) -
                  px * py * (4.0 * l * l * r2 - 6.0 * l);
  const real3 htc = (4.0 * xc) * y - (4.0 * l * py * xc) * r + (4.0 * l * px * rc) * y -
                    (px * py) * ((4.0 * l * l * rc) * r - (2.0 * l) * c);
  return psi * (tr * c - htc);
}

// u(x) = sum over centres [begin, end) of K(x, centre_j) coef_j.
inline real3 field_at(const real3 x, const int begin, const int end, __global const real* centres,
                      __global const real* coefs, const real l, const int tangent) {
  real3 u = (real3)(0.0, 0.0, 0.0);
  if (tangent) {
    for (int j = begin; j < end; ++j)
      u += apply_tangent(x, reg_load3(centres, j), reg_load3(coefs, j), l);
  } else {
    for (int j = begin; j < end; ++j)
      u += apply_free(x - reg_load3(centres, j), reg_load3(coefs, j), l);
  }
  return u;
}

// out[i] = u(x[i]) for the nc centres of one field.
__kernel void eval_field(const int n, __global const real* x, const int nc,
                         __global const real* centres, __global const real* coefs, const real l,
                         const int tangent, __global real* out) {
  const int i = get_global_id(0);
  if (i >= n) return;
  const real3 u = field_at(reg_load3(x, i), 0, nc, centres, coefs, l, tangent);
  out[3 * i] = u.x;
  out[3 * i + 1] = u.y;
  out[3 * i + 2] = u.z;
}

// Integrates dx/dt = u(x, t) over `steps` RK4 steps of length dt for every point. Field slot s
// (time s * dt / 2) has centres [slot[2s], slot[2s + 1]); step k uses slots 2k, 2k+1, 2k+2.
// The whole path of a point stays in registers: one launch for the whole advection.
__kernel void rk4_advect(const int n, __global real* x, const int steps, const real dt,
                         __global const int* slot, __global const real* centres,
                         __global const real* coefs, const real l, const int tangent) {
  const int i = get_global_id(0);
  if (i >= n) return;
  real3 p = reg_load3(x, i);
  for (int k = 0; k < steps; ++k) {
    __global const int* s = slot + 4 * k;  // slots 2k, 2k+1, 2k+2 as (begin, end) pairs
    const real3 k1 = field_at(p, s[0], s[1], centres, coefs, l, tangent);
    const real3 k2 = field_at(p + (0.5 * dt) * k1, s[2], s[3], centres, coefs, l, tangent);
    const real3 k3 = field_at(p + (0.5 * dt) * k2, s[2], s[3], centres, coefs, l, tangent);
    const real3 k4 = field_at(p + dt * k3, s[4], s[5], centres, coefs, l, tangent);
    p += (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  x[3 * i] = p.x;
  x[3 * i + 1] = p.y;
  x[3 * i + 2] = p.z;
}
