#include "support/shapes.hpp"

#include <algorithm>
#include <cmath>

#include "support/fixtures.hpp"
#include "vpm/geometry.hpp"

namespace vpm::test {

TetMesh box_mesh(int nx, int ny, int nz) {
  TetMesh m;
  const int sx = nx + 1, sy = ny + 1, sz = nz + 1;
  m.vertices.resize(sx * sy * sz, 3);
  auto id = [&](int i, int j, int k) { return i + sx * (j + sy * k); };
  for (int k = 0; k < sz; ++k)
    for (int j = 0; j < sy; ++j)
      for (int i = 0; i < sx; ++i)
        m.vertices.row(id(i, j, k)) << double(i) / nx, double(j) / ny, double(k) / nz;
  static constexpr int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  m.tets.resize(6 * nx * ny * nz, 4);
  int t = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
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

TetMesh ellipsoid_mesh(int n) {
  TetMesh m = ball_mesh(n);
  m.vertices.col(0) *= 1.8;
  m.vertices.col(2) *= 0.6;
  return m;
}

namespace {
// (y, z) in [-1,1]^2 -> disk of radius 1 (square shells to circles), keeps orientation.
void squircle(double& y, double& z) {
  const double inf = std::max(std::abs(y), std::abs(z)), r = std::hypot(y, z);
  if (r > 0) {
    y *= inf / r;
    z *= inf / r;
  }
}
void fix_orientation(TetMesh& m) {
  const Eigen::VectorXd vol = tet_volumes(m.vertices, m.tets);
  for (int i = 0; i < m.tets.rows(); ++i)
    if (vol(i) < 0) std::swap(m.tets(i, 2), m.tets(i, 3));
}
}  // namespace

TetMesh bent_mesh(int n) {
  TetMesh m = box_mesh(3 * n, n, n);
  const double arc = 1.5 * M_PI;
  for (int i = 0; i < m.num_vertices(); ++i) {
    const double x = m.vertices(i, 0), y = m.vertices(i, 1), z = m.vertices(i, 2);
    const double th = arc * x, r = 1.0 + 0.6 * y;
    m.vertices.row(i) << r * std::cos(th), r * std::sin(th), 0.6 * z;
  }
  fix_orientation(m);
  return m;
}

TetMesh dumbbell_mesh(int n) {
  TetMesh m = box_mesh(3 * n, n, n);
  for (int i = 0; i < m.num_vertices(); ++i) {
    const double x = 3.0 * m.vertices(i, 0);
    double y = 2.0 * m.vertices(i, 1) - 1.0, z = 2.0 * m.vertices(i, 2) - 1.0;
    squircle(y, z);
    const double rad = 0.6 - 0.35 * std::exp(-std::pow((x - 1.5) / 0.45, 2));
    m.vertices.row(i) << x, rad * y, rad * z;
  }
  fix_orientation(m);
  return m;
}

}  // namespace vpm::test
