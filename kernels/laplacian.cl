// Cotangent Laplacian values for moving vertices on a fixed CSR pattern (see vpm/laplacian.hpp).
// Positions n x 3 row-major; tets m x 4 row-major.

// Local edge index of corners (a, b): (0,1)=0 (0,2)=1 (0,3)=2 (1,2)=3 (1,3)=4 (2,3)=5.
__constant int kEdge[16] = {-1, 0, 1, 2, 0, -1, 3, 4, 1, 3, -1, 5, 2, 4, 5, -1};

// Per tet: the six off-diagonal stiffness entries K_ab = -(c_a . c_b) / (6 det) with
// c_1 = e2 x e3, c_2 = e3 x e1, c_3 = e1 x e2, c_0 = -(c_1 + c_2 + c_3) (det grad phi_a = c_a),
// and the signed volume det / 6.
__kernel void tet_weights(const int m, __global const real* x, __global const int* tets,
                          __global real* w, __global real* vol) {
  const int t = get_global_id(0);
  if (t >= m) return;
  const real3 p0 = load3(x, tets[4 * t]);
  const real3 e1 = load3(x, tets[4 * t + 1]) - p0;
  const real3 e2 = load3(x, tets[4 * t + 2]) - p0;
  const real3 e3 = load3(x, tets[4 * t + 3]) - p0;
  const real3 c1 = cross(e2, e3), c2 = cross(e3, e1), c3 = cross(e1, e2);
  const real3 c0 = -(c1 + c2 + c3);
  const real det = dot(e1, c1);
  const real s = -1.0 / (6.0 * det);
  w[6 * t + 0] = s * dot(c0, c1);
  w[6 * t + 1] = s * dot(c0, c2);
  w[6 * t + 2] = s * dot(c0, c3);
  w[6 * t + 3] = s * dot(c1, c2);
  w[6 * t + 4] = s * dot(c1, c3);
  w[6 * t + 5] = s * dot(c2, c3);
  vol[t] = det / 6.0;
}

// One work item per row: zero the row, then gather the weights of the incident tets through
// the slot map (slot[12 t + 3 a + q] = CSR index of (tets[t][a], tets[t][b_q])). No atomics:
// only work item i writes row i. Also the lumped mass (a quarter of the incident volumes).
__kernel void assemble_rows(const int n, __global const int* row_ptr,
                            __global const int* inc_offset, __global const int* inc_tet,
                            __global const int* tets, __global const int* slot,
                            __global const int* diag, __global const real* w,
                            __global const real* vol, __global real* val, __global real* mass) {
  const int i = get_global_id(0);
  if (i >= n) return;
  for (int k = row_ptr[i]; k < row_ptr[i + 1]; ++k) val[k] = 0.0;
  real d = 0.0, vs = 0.0;
  for (int k = inc_offset[i]; k < inc_offset[i + 1]; ++k) {
    const int t = inc_tet[k];
    int a = 0;
    for (int c = 1; c < 4; ++c)
      if (tets[4 * t + c] == i) a = c;
    for (int q = 0; q < 3; ++q) {
      const int b = q < a ? q : q + 1;
      const real ww = w[6 * t + kEdge[4 * a + b]];
      val[slot[12 * t + 3 * a + q]] += ww;
      d -= ww;
    }
    vs += vol[t];
  }
  val[diag[i]] = d;
  mass[i] = 0.25 * vs;
}
