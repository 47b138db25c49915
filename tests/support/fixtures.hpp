#pragma once
// Small meshes generated in code for tests (no files needed).
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

}  // namespace vpm::test
