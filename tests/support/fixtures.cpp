#include "support/fixtures.hpp"
#include "support/shapes.hpp"

#include <algorithm>
#include <cmath>

#include "vpm/geometry.hpp"

namespace vpm::test {

TetMesh cube_mesh(int n) { return box_mesh(n, n, n); }

TetMesh single_tet() {
  TetMesh m;
  m.vertices.resize(4, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  m.tets.resize(1, 4);
  m.tets << 0, 1, 2, 3;
  return m;
}

TetMesh ball_mesh(int n) {
  TetMesh m = cube_mesh(n);
  for (int i = 0; i < m.vertices.rows(); ++i) {
    Eigen::RowVector3d p = 2.0 * m.vertices.row(i).array() - 1.0;  // [-1,1]^3
    const double inf = p.cwiseAbs().maxCoeff();
    const double r = p.norm();
    if (r > 0) p *= inf / r;  // cube shell of "radius" inf -> sphere of radius inf
    m.vertices.row(i) = p;
  }
  return m;
}

}  // namespace vpm::test
