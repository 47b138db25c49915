#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <cmath>
#include <map>

#include "mesh/mesh_volumes.hpp"
#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "support/incompressible.hpp"
#include "vpm/device.hpp"
#include "vpm/geometry.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/error.hpp"
#include "vpm/metrics.hpp"

using namespace vpm;

TEST_CASE("tet volumes sum to the cube volume on every device") {
  const TetMesh m = test::cube_mesh(5);
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    const Eigen::VectorXd v = tet_volumes(*dev, m.vertices, m.tets);
    REQUIRE(v.size() == m.num_tets());
    CHECK(v.sum() == Approx(1.0).epsilon(1e-12));
    CHECK(v.minCoeff() > 0);
    CHECK(v.minCoeff() == Approx(1.0 / (6 * 125)).epsilon(1e-12));
  }
}

TEST_CASE("dual volumes sum to the total and host and device agree") {
  TetMesh m = test::ball_mesh(6);
  // perturb interior points so volumes differ
  for (int i = 0; i < m.num_vertices(); ++i) m.vertices.row(i) *= 1.0 + 0.01 * std::sin(7.0 * i);
  const Eigen::VectorXd host = dual_volumes(m.vertices, m.tets);
  const Eigen::VectorXd tv = tet_volumes(m.vertices, m.tets);
  CHECK(host.sum() == Approx(tv.sum()).epsilon(1e-12));
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    const Eigen::VectorXd d = dual_volumes(*dev, m.vertices, m.tets);
    CHECK((d - host).cwiseAbs().maxCoeff() <= 1e-15 * host.cwiseAbs().maxCoeff() * 10);
  }
}

TEST_CASE("volumes kept on the device (connectivity uploaded once) follow new positions") {
  const TetMesh m = test::ball_mesh(6);
  for (auto& dev : test::devices()) {
    if (dev->is_host()) continue;
    INFO("device " << dev->name());
    detail::MeshVolumes dv(*dev, m.tets);
    for (int k = 0; k < 3; ++k) {  // the same object at three shapes: nothing stale is reused
      Points x = m.vertices;
      for (int i = 0; i < m.num_vertices(); ++i) x.row(i) *= 1.0 + 0.02 * k * std::sin(5.0 * i + k);
      const Eigen::VectorXd tv = tet_volumes(x, m.tets), dual = dual_volumes(x, m.tets);
      CHECK((dv.tet_volumes(x) - tv).cwiseAbs().maxCoeff() <= 1e-14 * tv.cwiseAbs().maxCoeff());
      CHECK((dv.dual_volumes(x) - dual).cwiseAbs().maxCoeff() <= 1e-14 * dual.cwiseAbs().maxCoeff());
      CHECK((tet_volumes(*dev, x, m.tets) - tv).cwiseAbs().maxCoeff() <= 1e-14 * tv.cwiseAbs().maxCoeff());
    }
  }
}

TEST_CASE("a mirrored tet has negative volume") {
  TetMesh m = test::single_tet();
  CHECK(tet_volumes(m.vertices, m.tets)(0) == Approx(1.0 / 6));
  std::swap(m.tets(0, 0), m.tets(0, 1));
  CHECK(tet_volumes(m.vertices, m.tets)(0) == Approx(-1.0 / 6));
}

TEST_CASE("dihedral angles of the regular-corner tet") {
  const TetMesh m = test::single_tet();
  const auto a = dihedral_angles_deg(m.vertices, m.tets);
  // edges at the right-angle corner have 90 degree dihedral angles
  CHECK(a(0, 0) == Approx(90));
  CHECK(a(0, 1) == Approx(90));
  CHECK(a(0, 2) == Approx(90));
  // opposite edges: acos(1/sqrt(3)) = 54.7356
  CHECK(a(0, 3) == Approx(54.7356103).epsilon(1e-6));
}

TEST_CASE("metrics of the identity map and of a scaled map are zero distortion") {
  const TetMesh m = test::ball_mesh(4);
  for (auto& dev : test::devices()) {
    const Points scaled = 2.5 * m.vertices;
    const MapMetrics mm = map_metrics(*dev, m.vertices, scaled, m.tets);
    CHECK(mm.inverted_tets == 0);
    CHECK(mm.tet_volume_ratio.mean_abs_dev < 1e-12);
    CHECK(mm.vertex_volume_ratio.max_abs_log < 1e-12);
    CHECK(mm.boundary_max_radius_error == Approx(1.5).epsilon(1e-9));
  }
}

TEST_CASE("metrics count inverted tets and measure distortion") {
  const TetMesh m = test::cube_mesh(3);
  Points moved = m.vertices;
  // move an interior vertex far through its neighbours: some tets invert
  int interior = 1 + 4 * (1 + 4 * 1);
  moved.row(interior) << 2.0, 2.0, 2.0;
  auto host = Device::host();
  const MapMetrics mm = map_metrics(*host, m.vertices, moved, m.tets);
  CHECK(mm.inverted_tets > 0);
  CHECK(mm.tet_volume_ratio.mean_abs_dev > 0.01);
  CHECK(mm.tet_volume_ratio.max_abs_log > 100);  // inverted ratios enter as 1e-300
}

TEST_CASE("icosphere: 20 * 4^L outward triangles on the unit sphere, a closed genus-0 surface") {
  for (int level : {0, 1, 3}) {
    INFO("level " << level);
    const TriSurface s = icosphere(level);
    const long f = 20L << (2 * level);
    CHECK(s.triangles.rows() == f);
    CHECK(s.vertices.rows() == f / 2 + 2);  // Euler: V - E + F = 2 with E = 3F/2
    for (Eigen::Index i = 0; i < s.vertices.rows(); ++i) CHECK(std::abs(s.vertices.row(i).norm() - 1) < 1e-15);
    std::map<std::pair<int, int>, int> directed;
    double volume = 0;
    for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
      const Eigen::Vector3d a = s.vertices.row(s.triangles(t, 0)), b = s.vertices.row(s.triangles(t, 1)),
                            c = s.vertices.row(s.triangles(t, 2));
      const double v = a.dot(b.cross(c)) / 6;  // the tet (origin, a, b, c)
      CHECK(v > 0);                             // every triangle faces outward
      volume += v;
      for (int k = 0; k < 3; ++k) ++directed[{s.triangles(t, k), s.triangles(t, (k + 1) % 3)}];
    }
    // closed and consistently oriented: every directed edge once, its reverse once
    CHECK(directed.size() == static_cast<size_t>(3 * f));
    for (const auto& [e, n] : directed) {
      CHECK(n == 1);
      CHECK(directed.count({e.second, e.first}) == 1);
    }
    CHECK(volume < 4 * M_PI / 3);  // inscribed polyhedron
    if (level == 3) CHECK(volume > 0.99 * 4 * M_PI / 3);
  }
  CHECK_THROWS_AS(icosphere(-1), InputError);
  CHECK_THROWS_AS(icosphere(11), InputError);
}

TEST_CASE("the paper benchmark's deformation is divergence-free and keeps volumes") {
  test::IncompressibleFlow f;  // support/incompressible.hpp (bench/paper.cpp, Table 1)
  f.width = 0.35;
  f.centres = {{0.2, -0.1, 0.3}, {-0.3, 0.2, -0.1}};
  f.potentials = {{0.02, -0.03, 0.01}, {-0.01, 0.02, 0.03}};
  const double h = 1e-5;
  for (const Eigen::Vector3d x : {Eigen::Vector3d(0.1, 0.2, -0.3), Eigen::Vector3d(-0.4, 0.0, 0.25)}) {
    double div = 0;  // central differences: error O(h^2) plus round-off / h
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
      div += (f.velocity(x + e)(k) - f.velocity(x - e)(k)) / (2 * h);
    }
    CHECK(std::abs(div) < 1e-8);  // |grad u| is about 0.2 here
  }
  // the flow's Jacobian determinant is 1: small tets (edge 1e-4) keep their volume to the
  // first-order straight-edge error, while the flow moves them by about 0.05
  for (const Eigen::Vector3d p : {Eigen::Vector3d(0.1, 0.2, -0.3), Eigen::Vector3d(0.0, -0.2, 0.2)}) {
    Eigen::Matrix3d e0 = 1e-4 * Eigen::Matrix3d::Identity(), e1;
    for (int k = 0; k < 3; ++k) e1.col(k) = f.flow(p + e0.col(k)) - f.flow(p);
    CHECK((f.flow(p) - p).norm() > 0.01);
    CHECK(std::abs(e1.determinant() / e0.determinant() - 1) < 1e-4);
  }
}

TEST_CASE("the smallest dihedral angle per tet equals the row minima of the six angles") {
  // jittered tets of every shape, slivers and caps included, both orientations
  TetMesh m = test::jitter_interior(test::ball_mesh(5), 5, 0.45, 11);
  std::swap(m.tets(0, 2), m.tets(0, 3));  // one negatively oriented tet
  const auto all = dihedral_angles_deg(m.vertices, m.tets);
  const Eigen::VectorXd mins = min_dihedral_angles_deg(m.vertices, m.tets);
  REQUIRE(mins.size() == m.num_tets());
  double worst = 0;
  for (int t = 0; t < m.num_tets(); ++t) worst = std::max(worst, std::abs(mins(t) - all.row(t).minCoeff()));
  CHECK(worst <= 1e-9);
  CHECK(mins.minCoeff() < 20);  // the jitter made thin tets: the comparison covers them
  // a flat tet (zero-area face) has angle 0
  TetMesh flat = test::single_tet();
  flat.vertices.row(3) = flat.vertices.row(2);
  CHECK(min_dihedral_angles_deg(flat.vertices, flat.tets)(0) == 0.0);
}
