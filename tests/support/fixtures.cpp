#include "support/fixtures.hpp"
#include "support/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"

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

TetMesh jitter_interior(TetMesh m, int n, double amount, unsigned seed) {
  const auto bnd = boundary_vertex_mask(m.num_vertices(), boundary_faces(m.tets));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amount / n, amount / n);
  for (int i = 0; i < m.num_vertices(); ++i)
    if (!bnd[i]) m.vertices.row(i) += Eigen::RowVector3d(u(rng), u(rng), u(rng));
  return m;
}

TetMesh tunnel_cube() {
  TetMesh m = cube_mesh(3);
  std::vector<int> keep;
  for (int t = 0; t < m.num_tets(); ++t) {
    Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) c += m.vertices.row(m.tets(t, k)) / 4;
    if (!(c(0) > 1.0 / 3 && c(0) < 2.0 / 3 && c(1) > 1.0 / 3 && c(1) < 2.0 / 3)) keep.push_back(t);
  }
  Tets t2(static_cast<Eigen::Index>(keep.size()), 4);
  for (size_t i = 0; i < keep.size(); ++i) t2.row(static_cast<Eigen::Index>(i)) = m.tets.row(keep[i]);
  m.tets = t2;
  return m;
}

void random_landmarks(int n, unsigned seed, double radius, double reach, double max_radius, double move, Points& p,
                      Points& q) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  p.resize(n, 3);
  q.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d a, d;
    do a << u(gen), u(gen), u(gen);
    while (a.norm() > 1);
    a *= radius;
    do d << u(gen), u(gen), u(gen);
    while (d.norm() > 1 || (a + reach * d).norm() > max_radius);
    p.row(i) = a.transpose();
    q.row(i) = (a + move * d).transpose();
  }
}

Eigen::VectorXd zero_sum_random(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = g(rng);
  b.array() -= b.mean();
  return b;
}

}  // namespace vpm::test
