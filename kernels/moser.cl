// Moser rounds: point location in the round's background mesh, interpolation of the fixed
// field v(y, t) = grad psi(y) / ((1 - t) rho0(y) + t), and the RK4 stages. The point location
// (kernels/tet_locate.clh) and the field's expressions (kernels/moser_field.clh) are shared with
// the host (host/mesh/tet_grid.cpp, host/map/moser_field.cpp): these kernels only load, call
// and store.
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
#include "tet_geometry.clh"
#include "moser_field.clh"

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
  real p[3];
  for (int d = 0; d < 3; ++d) p[d] = x[3 * i + d] + c * kprev[3 * i + d];
  if (on_b) mf_unit(p);
  real l[4];
  int st[3] = {0, 0, 0};
  const int tet = locate((real3)(p[0], p[1], p[2]), hint[i], inv, nbr, lox, loy, loz, inv_h, gx,
                         gy, gz, cell_start, cell_tets, l, st);
  hint[i] = tet;
  real u[3];
  mf_velocity(tets + 4 * tet, l, grad, rho0, t, on_b, p, u);
  for (int d = 0; d < 3; ++d) vel[3 * i + d] = u[d];
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
  real p[3], a[3], b[3], c[3], d[3];
  for (int j = 0; j < 3; ++j) {
    p[j] = x[3 * i + j];
    a[j] = k1[3 * i + j];
    b[j] = k2[3 * i + j];
    c[j] = k3[3 * i + j];
    d[j] = k4[3 * i + j];
  }
  mf_rk4_step(p, a, b, c, d, dt, on_b);
  for (int j = 0; j < 3; ++j) x[3 * i + j] = p[j];
}

// ---- The round's field from psi (paper eq. 12-13) -------------------------------------------
// Per vertex: grad[v] = the volume-weighted mean of the gradients of psi on its tets (tets in
// increasing order, the CSR incidence offset / tet_of, as the host's vertex_gradients sums
// them; each tet's gradient mf_tet_gradient, its volume det[b-a, c-a, d-a] / 6 from x,
// recomputed for each of its 4 vertices rather than stored), then mf_boundary_gradient.
__kernel void moser_vertex_gradients(const int n, __global const int* offset,
                                     __global const int* tet_of, __global const int* tets,
                                     __global const real* inv, __global const real* psi,
                                     __global const char* boundary, const int slide,
                                     __global const real* x, __global real* grad) {
  const int v = get_global_id(0);
  if (v >= n) return;
  real w = 0.0;
  real g[3] = {0.0, 0.0, 0.0};
  for (int k = offset[v]; k < offset[v + 1]; ++k) {
    const int t = tet_of[k];
    __global const int* T = tets + 4 * t;
    const real p0 = psi[T[0]];
    real gt[3];
    mf_tet_gradient(inv + 12 * t, psi[T[1]] - p0, psi[T[2]] - p0, psi[T[3]] - p0, gt);
    real e1[3], e2[3], e3[3];
    tg_edges(x, T, e1, e2, e3);
    const real vol = tg_volume(e1, e2, e3);
    w += vol;
    for (int d = 0; d < 3; ++d) g[d] += vol * gt[d];
  }
  if (w > 0.0)
    for (int d = 0; d < 3; ++d) g[d] /= w;
  const real p[3] = {x[3 * v], x[3 * v + 1], x[3 * v + 2]};
  mf_boundary_gradient(boundary[v], slide, p, g);
  for (int d = 0; d < 3; ++d) grad[3 * v + d] = g[d];
}

// ---- The round's background on the device -----------------------------------------------
// inv of tet t from the positions x: its corner a, then the rows of M^-1 (tg_inverse_rows, as
// the host's build_background).
__kernel void moser_tet_inverses(const int m, __global const real* x, __global const int* tets,
                                 __global real* inv) {
  const int t = get_global_id(0);
  if (t >= m) return;
  __global const int* T = tets + 4 * t;
  real e1[3], e2[3], e3[3], rows[9];
  tg_edges(x, T, e1, e2, e3);
  tg_inverse_rows(e1, e2, e3, rows);
  __global real* q = inv + 12 * (size_t)t;
  for (int c = 0; c < 3; ++c) q[c] = x[3 * T[0] + c];
  for (int k = 0; k < 9; ++k) q[3 + k] = rows[k];
}
