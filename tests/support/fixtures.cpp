#include "support/fixtures.hpp"

#include <algorithm>
#include <cmath>

#include "vpm/geometry.hpp"

namespace vpm::test {

TetMesh cube_mesh(int n) {
  TetMesh m;
  const int s = n + 1;
  m.vertices.resize(s * s * s, 3);
  auto id = [s](int i, int j, int k) { return i + s * (j + s * k); };
  for (int k = 0; k < s; ++k)
    for (int j = 0; j < s; ++j)
      for (int i = 0; i < s; ++i) m.vertices.row(id(i, j, k)) << double(i) / n, double(j) / n, double(k) / n;
  // Kuhn subdivision: the 6 tets along paths from corner 000 to 111 through the cube.
  static constexpr int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  m.tets.resize(6 * n * n * n, 4);
  int t = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          int v[4];
          v[0] = id(c[0], c[1], c[2]);
          for (int q = 0; q < 3; ++q) {
            ++c[p[q]];
            v[q + 1] = id(c[0], c[1], c[2]);
          }
          m.tets.row(t++) << v[0], v[1], v[2], v[3];
        }
  const Eigen::VectorXd vol = tet_volumes(m.vertices, m.tets);
  for (int i = 0; i < m.tets.rows(); ++i)
    if (vol(i) < 0) std::swap(m.tets(i, 2), m.tets(i, 3));
  return m;
}

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
