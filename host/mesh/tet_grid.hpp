#pragma once
// Private: point location in a tet mesh (barycentric coordinates, walks through face
// neighbours, a uniform grid fallback), used by vpm::TetLocator (vpm/locate.hpp) and by the
// volume map's Moser field (map/moser_field.hpp). The walk is kernels/tet_locate.clh, compiled
// both here and in kernels/moser.cl.
#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "core/uninitialized.hpp"
#include "vpm/mesh.hpp"

namespace vpm::detail {

// The walk, shared with the kernels (kernels/moser.cl and kernels/sampling.cl include it too).
#include "kernels/tet_locate.clh"

/// nbr[4 t + k] = the tet sharing the face of tet t opposite its corner k, or -1 (boundary).
/// `boundary`, when given, receives vpm::boundary_faces(tets) from the same face sort.
std::vector<int> tet_neighbors(const Tets& tets, Triangles* boundary = nullptr);

/// A tet mesh prepared for point location: per-tet affine maps for barycentric coordinates,
/// face neighbours for walks, and a uniform grid of tets for the fallback search.
struct TetGrid {
  int n = 0, m = 0;
  const Tets* tets = nullptr;        ///< m x 4 (owned by the caller)
  const std::vector<int>* nbr = nullptr;
  UninitVector<double> inv;          ///< m x 12: corner a, then rows of [b-a, c-a, d-a]^-1 (filled in parallel)
  double lo[3] = {0, 0, 0};
  double inv_h = 1;
  int dims[3] = {1, 1, 1};
  std::vector<int> cell_start;       ///< cells + 1
  UninitVector<int> cell_tets;       ///< the tets of each cell, cells in order (filled in parallel)
};

/// Fills inv and the grid of `f` for background positions `x` (n x 3).
void build_background(TetGrid& f, const Points& x, const Tets& tets, const std::vector<int>& nbr);

/// The same without inv (left empty): for a background whose inverse matrices are made where
/// it is used (DeviceAdvector::set_field with psi).
void build_grid(TetGrid& f, const Points& x, const Tets& tets, const std::vector<int>& nbr);

/// Barycentric coordinates l[0..3] of `p` in tet `t` of the background `f`.
void bary(const TetGrid& f, int t, const Eigen::Vector3d& p, double* l);

/// The walk's view of `f` (kernels/tet_locate.clh): its grid, pointing into f's arrays.
TlGrid tl_grid(const TetGrid& f);

/// The tet a location of `p` without a hint starts from: the first tet of p's grid cell.
int start_tet(const TetGrid& f, const Eigen::Vector3d& p);

/// Point location: walks from tet `t` towards `p` through face neighbours (at most 64 steps),
/// else searches the grid cell of `p`. Returns the tet containing `p` with its barycentric
/// coordinates in `l`; a point outside the mesh gets the best tet found and coordinates clamped
/// to it. `st` (3 counters: walk steps, grid fallbacks, clamped) is incremented.
int locate(const TetGrid& f, const Eigen::Vector3d& p, int t, double* l, long long* st);

}  // namespace vpm::detail
