#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <random>

#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/laplacian.hpp"
#include "vpm/topology.hpp"

using namespace vpm;

namespace {
// A cube mesh with interior vertices jittered (keeps tets positive for small jitter), so the
// weights are irregular and some are negative.
TetMesh jittered_cube(int n, double amount, unsigned seed = 7) {
  return test::jitter_interior(test::cube_mesh(n), n, amount, seed);
}

double max_abs(const CsrMatrix& a) {
  double s = 0;
  for (double v : a.val) s = std::max(s, std::abs(v));
  return s;
}
}  // namespace

TEST_CASE("cotangent Laplacian of the corner tet matches hand values") {
  const TetMesh m = test::single_tet();
  const CsrMatrix k = cotan_laplacian(m.vertices, m.tets);
  CHECK(k.coeff(0, 1) == Approx(1.0 / 6));
  CHECK(k.coeff(0, 2) == Approx(1.0 / 6));
  CHECK(k.coeff(1, 2) == Approx(0.0).margin(1e-15));
  CHECK(k.coeff(0, 0) == Approx(-0.5));
  CHECK(k.coeff(1, 1) == Approx(-1.0 / 6));
}

TEST_CASE("cotangent Laplacian: symmetric, zero row sums, kills linear fields inside") {
  const TetMesh m = jittered_cube(6, 0.3);
  const int n = m.num_vertices();
  const CsrMatrix k = cotan_laplacian(m.vertices, m.tets);
  const double scale = max_abs(k);
  bool negative_weight = false;
  for (int i = 0; i < n; ++i) {
    double row = 0;
    for (int q = k.row_ptr[i]; q < k.row_ptr[i + 1]; ++q) {
      row += k.val[q];
      const int j = k.col[q];
      REQUIRE(k.find(j, i) >= 0);
      CHECK(std::abs(k.val[q] - k.coeff(j, i)) <= 1e-14 * scale);
      if (j != i && k.val[q] < 0) negative_weight = true;
    }
    CHECK(std::abs(row) <= 1e-13 * scale);
    CHECK(k.coeff(i, i) < 0);
  }
  CHECK(negative_weight);  // the jitter makes some dihedral angles obtuse
  const auto bnd = boundary_vertex_mask(n, boundary_faces(m.tets));
  for (int c = 0; c < 3; ++c) {
    Eigen::VectorXd lin = m.vertices.col(c) * (c + 1.5) + Eigen::VectorXd::Constant(n, 0.25);
    const Eigen::VectorXd y = k.multiply(lin);
    for (int i = 0; i < n; ++i)
      if (!bnd[i]) CHECK(std::abs(y[i]) <= 1e-12 * scale);
  }
  // -K is positive semi-definite: x^T K x <= 0 for random x.
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  Eigen::VectorXd r(n);
  for (int i = 0; i < n; ++i) r[i] = g(rng);
  CHECK(r.dot(k.multiply(r)) < 0);
}

TEST_CASE("cotangent Laplacian equals the per-edge dihedral-angle formula") {
  const TetMesh m = jittered_cube(4, 0.3, 11);
  const CsrMatrix k = cotan_laplacian(m.vertices, m.tets);
  const auto ang = dihedral_angles_deg(m.vertices, m.tets);
  static constexpr int ends[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  std::map<std::pair<int, int>, double> w;
  for (int t = 0; t < m.num_tets(); ++t)
    for (int e = 0; e < 6; ++e) {
      const int o = 5 - e;  // the opposite edge
      const int i = m.tets(t, ends[e][0]), j = m.tets(t, ends[e][1]);
      const Eigen::RowVector3d d = m.vertices.row(m.tets(t, ends[o][0])) - m.vertices.row(m.tets(t, ends[o][1]));
      const double theta = ang(t, o) * M_PI / 180.0;
      w[{std::min(i, j), std::max(i, j)}] += d.norm() / std::tan(theta) / 6.0;
    }
  const double scale = max_abs(k);
  int checked = 0;
  for (const auto& [ij, value] : w) {
    CHECK(std::abs(k.coeff(ij.first, ij.second) - value) <= 1e-9 * scale);
    ++checked;
  }
  // every off-diagonal entry of the pattern is an edge
  CHECK(checked == (k.nnz() - k.rows) / 2);
}

TEST_CASE("CotanLaplacian class: host and device equal the reference, and track moving vertices") {
  TetMesh m = jittered_cube(5, 0.25, 5);
  const int n = m.num_vertices();
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    CotanLaplacian lap(n, m.tets);
    CHECK(lap.nnz() == cotan_laplacian(m.vertices, m.tets).nnz());
    for (int step = 0; step < 3; ++step) {
      Points x = m.vertices;
      for (int i = 0; i < n; ++i) x.row(i) *= 1.0 + 0.05 * step * std::sin(3.0 * i);
      lap.assemble(*dev, x);
      const CsrMatrix ref = cotan_laplacian(x, m.tets);
      const CsrMatrix& k = lap.matrix();
      REQUIRE(k.row_ptr == ref.row_ptr);
      REQUIRE(k.col == ref.col);
      const double scale = max_abs(ref);
      double diff = 0;
      for (int q = 0; q < k.nnz(); ++q) diff = std::max(diff, std::abs(k.val[q] - ref.val[q]));
      CHECK(diff <= 1e-13 * scale);
      const Eigen::VectorXd dv = dual_volumes(x, m.tets);
      CHECK((lap.mass() - dv).cwiseAbs().maxCoeff() <= 1e-14 * dv.cwiseAbs().maxCoeff() * 10);
      CHECK(lap.mass().sum() == Approx(tet_volumes(x, m.tets).sum()).epsilon(1e-12));
    }
  }
}

TEST_CASE("CotanLaplacian rejects out-of-range indices and converts to and from Eigen") {
  TetMesh m = test::single_tet();
  Tets bad = m.tets;
  bad(0, 2) = 9;
  CHECK_THROWS_AS(CotanLaplacian(4, bad), InputError);
  const CsrMatrix k = cotan_laplacian(m.vertices, m.tets);
  const CsrMatrix back = CsrMatrix::from_eigen(k.to_eigen());
  CHECK(back.row_ptr == k.row_ptr);
  CHECK(back.col == k.col);
  CHECK(back.val == k.val);
  Eigen::SparseMatrix<double> cm = k.to_eigen();
  const CsrMatrix back2 = CsrMatrix::from_eigen(cm);
  CHECK(back2.val == k.val);
}
