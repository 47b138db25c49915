#pragma once
// Private: a tet's volume and inverse edge matrix on the host, from kernels/tet_geometry.clh (the
// expressions the kernels compile too: tg_dot, tg_cross, tg_length, tg_edges, tg_volume,
// tg_inverse_rows), and the edges of a mesh's tet.
#include <cmath>

#include "vpm/mesh.hpp"

namespace vpm::detail {

#include "kernels/tet_geometry.clh"

/// The edges e[0..2] = b - a, c - a, d - a of tet t (corners a, b, c, d) at positions x.
inline void tet_edges(const Points& x, const Tets& tets, int t, double (&e)[3][3]) {
  tg_edges(x.data(), tets.data() + 4 * static_cast<Eigen::Index>(t), e[0], e[1], e[2]);
}

}  // namespace vpm::detail
