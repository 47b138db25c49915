#pragma once
// Private: a tet's volume and inverse edge matrix on the host, from kernels/tet_geometry.clh (the
// expressions the kernels compile too: tg_dot, tg_cross, tg_length, tg_volume,
// tg_inverse_rows), and the edges of a mesh's tet.
#include <cmath>

#include "vpm/mesh.hpp"

namespace vpm::detail {

#include "kernels/tet_geometry.clh"

/// The edges e[0..2] = b - a, c - a, d - a of tet t (corners a, b, c, d) at positions x.
inline void tet_edges(const Points& x, const Tets& tets, int t, double (&e)[3][3]) {
  for (int c = 0; c < 3; ++c) {
    const double a = x(tets(t, 0), c);
    for (int k = 0; k < 3; ++k) e[k][c] = x(tets(t, k + 1), c) - a;
  }
}

}  // namespace vpm::detail
