#pragma once
// Synthetic solids for the initial-map and untangling tests, built by mapping structured
// box meshes (Kuhn subdivision, positively oriented, boundary a topological sphere).
#include "vpm/mesh.hpp"

namespace vpm::test {

/// The box [0,nx/n]x[0,ny/n]x[0,nz/n] (unit spacing 1/n... see below) as nx*ny*nz cells of 6
/// tets each: vertex (i,j,k) at (i/nx, j/ny, k/nz) of the unit cube. (nx+1)(ny+1)(nz+1) vertices.
TetMesh box_mesh(int nx, int ny, int nz);

/// Convex: ball_mesh(n) scaled to the ellipsoid with semi-axes 1.8 : 1 : 0.6.
TetMesh ellipsoid_mesh(int n);

/// Non-convex: a slab 3n x n x n cells bent into a C (270 degrees of arc, inner radius 1,
/// cross-section 0.6 x 0.6).
TetMesh bent_mesh(int n);

/// Non-convex: a rod 3n x n x n cells of length 3 with a round cross-section whose radius
/// goes 0.6 -> 0.25 (neck in the middle) -> 0.6.
TetMesh dumbbell_mesh(int n);

/// Convex, irregular (the solver benchmark's problems): the cells of a grid of spacing h whose
/// centre lies inside the ellipsoid (x/1.8)^2 + y^2 + (z/0.6)^2 <= 1, each Kuhn-subdivided into
/// 6 positively oriented tets, with h chosen so that about `target_tets` tets result; interior
/// vertices (24 incident tets) jittered by up to 0.15 h in each coordinate, drawn from
/// std::mt19937(seed). Vertices are numbered in order of first use, cells in x-fastest order.
TetMesh voxel_ellipsoid_mesh(long target_tets, unsigned seed = 1);

/// A smoother ball mesh than ball_mesh (whose shell-by-shell projection flattens tets at every
/// shell's corners): cube_mesh(n) on [-1,1]^3 through the elliptical cube-to-ball map, smooth
/// inside, the unit sphere on the boundary.
TetMesh smooth_ball_mesh(int n);

}  // namespace vpm::test
