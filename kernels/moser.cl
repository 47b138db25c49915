// Moser rounds: point location in the round's background mesh, interpolation of the fixed
// field v(y, t) = grad psi(y) / ((1 - t) rho0(y) + t), and the RK4 stages.
// The point location is shared with the host (kernels/tet_locate.clh); the field interpolation
// and the RK4 stages must match host/map/moser_field.cpp.
//
// Background data (uploaded once per round):
//   inv   m x 12: corner a (3), then the rows of [b-a, c-a, d-a]^-1 (9): lambda_{1..3} = Minv (p - a)
//         (uploaded from the host, or made here by moser_tet_inverses)
//   tets  m x 4, nbr m x 4 (tet across the face opposite corner k, -1 on the boundary)
//   grad  n x 3 vertex gradients of psi, rho0 n
//   grid: lo (3), inv_h, dims (3); cell_start (cells + 1), cell_tets
// Per point: x n x 3, hint n (containing tet of the last location), stats n x 3
// (walk steps, grid fallbacks, clamped-outside count).

#include "tet_locate.clh"

// Locates p from tet t (kernels/tet_locate.clh, shared with the host's reference).
inline int locate(real3 p, int t, __global const real* inv, __global const int* nbr,
                  const real lox, const real loy, const real loz, const real inv_h,
                  const int gx, const int gy, const int gz, __global const int* cell_start,
                  __global const int* cell_tets, real* l, int* st) {
  TlGrid g;
  g.lo[0] = lox;
  g.lo[1] = loy;
  g.lo[2] = loz;
  g.inv_h = inv_h;
  g.dims[0] = gx;
  g.dims[1] = gy;
  g.dims[2] = gz;
  g.cell_start = cell_start;
  g.cell_tets = cell_tets;
  return tl_locate(p.x, p.y, p.z, t, inv, nbr, &g, l, st);
}

// vel[i] = v(p, t) at p = x[i] + c * kprev[i] (boundary points renormalised to radius 1 when
// sliding; zero velocity when the boundary is fixed).
__kernel void moser_velocity(const int n, __global const real* x, __global const real* kprev,
                             const real c, const real t, const int slide,
                             __global const char* boundary, __global int* hint,
                             __global const real* inv, __global const int* tets,
                             __global const int* nbr, __global const real* grad,
                             __global const real* rho0, const real lox, const real loy,
                             const real loz, const real inv_h, const int gx, const int gy,
                             const int gz, __global const int* cell_start,
                             __global const int* cell_tets, __global real* vel,
                             __global int* stats) {
  const int i = get_global_id(0);
  if (i >= n) return;
  const int on_b = boundary[i];
  if (on_b && !slide) {
    vel[3 * i] = 0.0;
    vel[3 * i + 1] = 0.0;
    vel[3 * i + 2] = 0.0;
    return;
  }
  real3 p = load3(x, i) + c * load3(kprev, i);
  if (on_b) p = p / length(p);
  real l[4];
  int st[3] = {0, 0, 0};
  const int tet = locate(p, hint[i], inv, nbr, lox, loy, loz, inv_h, gx, gy, gz, cell_start,
                         cell_tets, l, st);
  hint[i] = tet;
  real3 g = (real3)(0.0, 0.0, 0.0);
  real r = 0.0;
  for (int k = 0; k < 4; ++k) {
    const int v = tets[4 * tet + k];
    g += l[k] * load3(grad, v);
    r += l[k] * rho0[v];
  }
  real3 u = g / ((1.0 - t) * r + t);
  if (on_b) {
    const real3 nrm = p;  // unit
    u -= dot(u, nrm) * nrm;
  }
  vel[3 * i] = u.x;
  vel[3 * i + 1] = u.y;
  vel[3 * i + 2] = u.z;
  stats[3 * i] += st[0];
  stats[3 * i + 1] += st[1];
  stats[3 * i + 2] += st[2];
}

// x += dt/6 (k1 + 2 k2 + 2 k3 + k4); boundary points renormalised to radius 1 when sliding.
__kernel void moser_rk_update(const int n, __global real* x, __global const real* k1,
                              __global const real* k2, __global const real* k3,
                              __global const real* k4, const real dt, const int slide,
                              __global const char* boundary) {
  const int i = get_global_id(0);
  if (i >= n) return;
  const int on_b = boundary[i];
  if (on_b && !slide) return;
  real3 p = load3(x, i) + (dt / 6.0) * (load3(k1, i) + 2.0 * load3(k2, i) + 2.0 * load3(k3, i) + load3(k4, i));
  if (on_b) p = p / length(p);
  x[3 * i] = p.x;
  x[3 * i + 1] = p.y;
  x[3 * i + 2] = p.z;
}

// ---- The round's field from psi (paper eq. 12-13) -------------------------------------------
// Must match tet_gradients (host/map/moser_field.cpp) and vertex_gradients
// (host/map/volume_map_steps.cpp): the same products and sums in the same order.

// Per vertex: grad[v] = the volume-weighted mean of the gradients of psi on its tets (tets in
// increasing order, the CSR incidence offset / tet_of; each tet's gradient is
// sum_j (psi_j - psi_0) * row j of Minv, its volume det[b-a, c-a, d-a] / 6 from x, recomputed
// for each of its 4 vertices rather than stored); at boundary vertices the normal part x/|x|
// is removed when sliding, the whole vector when the boundary is fixed.
__kernel void moser_vertex_gradients(const int n, __global const int* offset,
                                     __global const int* tet_of, __global const int* tets,
                                     __global const real* inv, __global const real* psi,
                                     __global const char* boundary, const int slide,
                                     __global const real* x, __global real* grad) {
  const int v = get_global_id(0);
  if (v >= n) return;
  real w = 0.0, gx = 0.0, gy = 0.0, gz = 0.0;
  for (int k = offset[v]; k < offset[v + 1]; ++k) {
    const int t = tet_of[k];
    __global const int* T = tets + 4 * t;
    __global const real* q = inv + 12 * t;
    const real p0 = psi[T[0]];
    const real d1 = psi[T[1]] - p0, d2 = psi[T[2]] - p0, d3 = psi[T[3]] - p0;
    const real3 a = load3(x, T[0]);
    const real3 e1 = load3(x, T[1]) - a, e2 = load3(x, T[2]) - a, e3 = load3(x, T[3]) - a;
    const real vol = dot(e1, cross(e2, e3)) / 6.0;
    w += vol;
    gx += vol * (d1 * q[3] + d2 * q[6] + d3 * q[9]);
    gy += vol * (d1 * q[4] + d2 * q[7] + d3 * q[10]);
    gz += vol * (d1 * q[5] + d2 * q[8] + d3 * q[11]);
  }
  real3 g = (real3)(gx, gy, gz);
  if (w > 0.0) g /= w;
  if (boundary[v]) {
    if (!slide) {
      g = (real3)(0.0, 0.0, 0.0);
    } else {
      const real3 p = load3(x, v);
      const real3 nrm = p / sqrt(dot(p, p));
      g -= dot(g, nrm) * nrm;
    }
  }
  grad[3 * v] = g.x;
  grad[3 * v + 1] = g.y;
  grad[3 * v + 2] = g.z;
}

// ---- The round's background on the device -----------------------------------------------
// inv of tet t from the positions x: its corner a, then the rows of M^-1 for the columns
// e1, e2, e3 = b - a, c - a, d - a of M, i.e. (e2 x e3, e3 x e1, e1 x e2) / det M. The host's
// build_background (Eigen's cofactor inverse) gives the same to round-off.
__kernel void moser_tet_inverses(const int m, __global const real* x, __global const int* tets,
                                 __global real* inv) {
  const int t = get_global_id(0);
  if (t >= m) return;
  __global const int* T = tets + 4 * t;
  const real3 a = load3(x, T[0]);
  const real3 e1 = load3(x, T[1]) - a, e2 = load3(x, T[2]) - a, e3 = load3(x, T[3]) - a;
  const real3 r1 = cross(e2, e3), r2 = cross(e3, e1), r3 = cross(e1, e2);
  const real inv_det = 1.0 / dot(e1, r1);
  __global real* q = inv + 12 * (size_t)t;
  q[0] = a.x;
  q[1] = a.y;
  q[2] = a.z;
  q[3] = r1.x * inv_det;
  q[4] = r1.y * inv_det;
  q[5] = r1.z * inv_det;
  q[6] = r2.x * inv_det;
  q[7] = r2.y * inv_det;
  q[8] = r2.z * inv_det;
  q[9] = r3.x * inv_det;
  q[10] = r3.y * inv_det;
  q[11] = r3.z * inv_det;
}
