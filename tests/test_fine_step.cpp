// The mesh displacement of dense registration's fine steps (register/fine_step.hpp).
#include <catch2/catch.hpp>

#include <cmath>

#include "register/fine_step.hpp"
#include "support/fixtures.hpp"
#include "vpm/error.hpp"
#include "vpm/topology.hpp"

using namespace vpm;

namespace {

std::vector<char> boundary_of(const TetMesh& m) {
  return boundary_vertex_mask(static_cast<int>(m.vertices.rows()), boundary_faces(m.tets));
}

// Systems asking every vertex for translation t (a = I, b = t), or only vertex `only` (-1: all).
LocalSystems translation_systems(Eigen::Index n, const Eigen::Vector3d& t, Eigen::Index only = -1) {
  LocalSystems s;
  s.b = Points::Zero(n, 3);
  for (Eigen::Index v = 0; v < n; ++v) {
    const bool on = only < 0 || v == only;
    s.a.push_back(on ? Eigen::Matrix3d(Eigen::Matrix3d::Identity()) : Eigen::Matrix3d(Eigen::Matrix3d::Zero()));
    if (on) s.b.row(v) = t.transpose();
  }
  return s;
}

}  // namespace

TEST_CASE("fine step: without smoothness each vertex takes its own system's answer, surface vertices tangentially") {
  const TetMesh m = test::ball_mesh(6);
  const std::vector<char> boundary = boundary_of(m);
  const Eigen::Vector3d t(0.01, -0.02, 0.015);
  const Points u = fine_displacement(translation_systems(m.vertices.rows(), t), m.vertices, m.tets, boundary, 0, 1);
  int surface = 0;
  for (Eigen::Index v = 0; v < m.vertices.rows(); ++v) {
    const Eigen::Vector3d n = m.vertices.row(v).transpose().normalized();
    const Eigen::Vector3d want = boundary[static_cast<size_t>(v)] ? Eigen::Vector3d(t - t.dot(n) * n) : t;
    // the floor of 1e-3 (in units of the mean trace / 3) shrinks every answer by 1 / (1 + 1e-3)
    CHECK((u.row(v).transpose() - want / 1.001).norm() < 1e-7);  // CG to a relative 1e-6
    if (boundary[static_cast<size_t>(v)]) {
      CHECK(std::abs(u.row(v).dot(n.transpose())) < 1e-12);
      ++surface;
    }
  }
  CHECK(surface > 0);
}

TEST_CASE("fine step: the membrane spreads one vertex's data to its neighbours, fading with distance") {
  const TetMesh m = test::ball_mesh(8);
  const std::vector<char> boundary = boundary_of(m);
  Eigen::Index centre = 0;  // the vertex nearest the middle
  m.vertices.rowwise().norm().minCoeff(&centre);
  const Eigen::Vector3d t(0.02, 0, 0);
  const LocalSystems one = translation_systems(m.vertices.rows(), t, centre);
  const Points alone = fine_displacement(one, m.vertices, m.tets, boundary, 0, 1);
  const Points spread = fine_displacement(one, m.vertices, m.tets, boundary, 0.05, 1);
  const auto edges = unique_edges(m.tets);
  int neighbours = 0;
  for (Eigen::Index e = 0; e < edges.rows(); ++e) {
    if (edges(e, 0) != centre && edges(e, 1) != centre) continue;
    const Eigen::Index nb = edges(e, 0) == centre ? edges(e, 1) : edges(e, 0);
    ++neighbours;
    CHECK(alone.row(nb).norm() < 1e-12);          // no membrane: nothing reaches the neighbours
    CHECK(spread(nb, 0) > 0);                      // with it they follow the data's direction
    CHECK(spread(nb, 0) < spread(centre, 0));      // but less than the vertex that has the data
  }
  CHECK(neighbours > 3);
  Eigen::Index far = 0;
  (m.vertices.rowwise() - m.vertices.row(centre)).rowwise().norm().maxCoeff(&far);
  CHECK(std::abs(spread(far, 0)) < 0.1 * spread(centre, 0));
}

TEST_CASE("fine step: displacements are capped, mismatched inputs are refused") {
  const TetMesh m = test::ball_mesh(5);
  const std::vector<char> boundary = boundary_of(m);
  const LocalSystems big = translation_systems(m.vertices.rows(), Eigen::Vector3d(1, 1, 1));
  const Points u = fine_displacement(big, m.vertices, m.tets, boundary, 1, 0.01);
  CHECK(u.rowwise().norm().maxCoeff() <= 0.01 + 1e-15);
  CHECK(u.rowwise().norm().maxCoeff() > 0.009);
  LocalSystems short_one = big;
  short_one.a.pop_back();
  CHECK_THROWS_AS(fine_displacement(short_one, m.vertices, m.tets, boundary, 1, 0.01), InputError);
  std::vector<char> short_mask = boundary;
  short_mask.pop_back();
  CHECK_THROWS_AS(fine_displacement(big, m.vertices, m.tets, short_mask, 1, 0.01), InputError);
}
