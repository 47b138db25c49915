#pragma once
// Small meshes generated in code for tests (no files needed).
#include <Eigen/Core>

#include "vpm/mesh.hpp"

namespace vpm::test {

/// The unit cube [0,1]^3 split into n^3 cells of 6 tets each (Kuhn/Freudenthal subdivision),
/// positively oriented. (n+1)^3 vertices, 6 n^3 tets; boundary is a sphere topologically.
TetMesh cube_mesh(int n);

/// A single positively oriented tet.
TetMesh single_tet();

/// A ball-like mesh: cube_mesh(n) centred at the origin, each point radially moved so the
/// cube's surface lies on the unit sphere ("squircle" map), keeping all tets positive.
TetMesh ball_mesh(int n);

/// `m` with its interior (non-boundary) vertices moved by uniform random offsets of up to
/// amount / n per coordinate (std::mt19937 seeded with `seed`), so cotangent weights become
/// irregular and some negative while small amounts keep every tet positive.
TetMesh jitter_interior(TetMesh m, int n, double amount, unsigned seed);

/// Landmark pairs for registration tests and benchmarks (std::mt19937 seeded with `seed`): n
/// sources uniform in the ball of radius `radius`; each moved by move x d, d uniform in the unit
/// ball and redrawn until source + reach x d lies within `max_radius`. Rows of p (sources), q.
void random_landmarks(int n, unsigned seed, double radius, double reach, double max_radius, double move, Points& p,
                      Points& q);

/// n standard normal values (std::mt19937 seeded with `seed`) with their mean removed: a
/// compatible right-hand side for Neumann problems.
Eigen::VectorXd zero_sum_random(int n, unsigned seed);

/// cube_mesh(3) without its centre column of cells: a solid torus (boundary genus 1).
TetMesh tunnel_cube();

}  // namespace vpm::test
