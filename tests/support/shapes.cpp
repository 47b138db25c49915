#include "support/shapes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

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

TetMesh voxel_ellipsoid_mesh(long target_tets, unsigned seed) {
  const double a = 1.8, b = 1.0, c = 0.6;
  const double h = std::cbrt(6.0 * (4.0 * M_PI / 3.0) * a * b * c / double(target_tets));
  const int nx = int(std::ceil(2 * a / h)) + 1, ny = int(std::ceil(2 * b / h)) + 1,
            nz = int(std::ceil(2 * c / h)) + 1;
  auto inside = [&](double x, double y, double z) {
    return (x / a) * (x / a) + (y / b) * (y / b) + (z / c) * (z / c) <= 1.0;
  };
  // grid of (nx+1)(ny+1)(nz+1) points centred on the origin
  const double ox = -0.5 * nx * h, oy = -0.5 * ny * h, oz = -0.5 * nz * h;
  const long sx = nx + 1, sy = ny + 1, sz = nz + 1;
  std::vector<int> id(size_t(sx * sy * sz), -1);
  auto gid = [&](long i, long j, long k) { return i + sx * (j + sy * k); };
  static constexpr int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  std::vector<std::array<int, 4>> tets;
  std::vector<std::array<double, 3>> pts;
  for (long k = 0; k < nz; ++k)
    for (long j = 0; j < ny; ++j)
      for (long i = 0; i < nx; ++i) {
        if (!inside(ox + (i + 0.5) * h, oy + (j + 0.5) * h, oz + (k + 0.5) * h)) continue;
        for (const auto& p : perms) {
          long cc[3] = {i, j, k};
          std::array<int, 4> t;
          for (int q = 0; q < 4; ++q) {
            if (q > 0) ++cc[p[q - 1]];
            const long g = gid(cc[0], cc[1], cc[2]);
            if (id[g] < 0) {
              id[g] = int(pts.size());
              pts.push_back({ox + cc[0] * h, oy + cc[1] * h, oz + cc[2] * h});
            }
            t[q] = id[g];
          }
          tets.push_back(t);
        }
      }
  TetMesh m;
  m.vertices.resize(long(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) m.vertices.row(long(i)) << pts[i][0], pts[i][1], pts[i][2];
  m.tets.resize(long(tets.size()), 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    const auto& v = tets[t];
    const Eigen::Vector3d p0 = m.vertices.row(v[0]);
    const Eigen::Vector3d e1 = m.vertices.row(v[1]).transpose() - p0;
    const Eigen::Vector3d e2 = m.vertices.row(v[2]).transpose() - p0;
    const Eigen::Vector3d e3 = m.vertices.row(v[3]).transpose() - p0;
    if (e1.dot(e2.cross(e3)) < 0) m.tets.row(long(t)) << v[0], v[1], v[3], v[2];
    else m.tets.row(long(t)) << v[0], v[1], v[2], v[3];
  }
  // jitter the interior vertices: those with all 24 incident tets of a Kuhn grid
  std::vector<int> count(pts.size(), 0);
  for (const auto& t : tets)
    for (int v : t) ++count[v];
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.15 * h, 0.15 * h);
  for (size_t i = 0; i < pts.size(); ++i)
    if (count[i] == 24)
      m.vertices.row(long(i)) += Eigen::RowVector3d(u(rng), u(rng), u(rng));
  return m;
}

// A smoother ball mesh than test::ball_mesh (whose shell-by-shell projection flattens tets at
// every shell's corners): cube_mesh(n) on [-1,1]^3 through the elliptical cube-to-ball map
// x' = x sqrt(1 - y^2/2 - z^2/2 + y^2 z^2/3) (and cyclic), smooth inside, sphere on the boundary.
TetMesh smooth_ball_mesh(int n) {
  TetMesh m = cube_mesh(n);
  for (int i = 0; i < m.vertices.rows(); ++i) {
    const double x = 2 * m.vertices(i, 0) - 1, y = 2 * m.vertices(i, 1) - 1, z = 2 * m.vertices(i, 2) - 1;
    m.vertices.row(i) << x * std::sqrt(std::max(0.0, 1 - y * y / 2 - z * z / 2 + y * y * z * z / 3)),
        y * std::sqrt(std::max(0.0, 1 - z * z / 2 - x * x / 2 + z * z * x * x / 3)),
        z * std::sqrt(std::max(0.0, 1 - x * x / 2 - y * y / 2 + x * x * y * y / 3));
  }
  return m;
}

}  // namespace vpm::test
