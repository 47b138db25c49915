#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include "support/fixtures.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"

using namespace vpm;

TEST_CASE("boundary of a cube mesh is a closed sphere with outward normals") {
  const TetMesh m = test::cube_mesh(3);
  const Triangles bf = boundary_faces(m.tets);
  CHECK(bf.rows() == 6 * 9 * 2);
  const SurfaceTopology st = surface_topology(m.num_vertices(), bf);
  CHECK(st.euler == 2);
  CHECK(st.components == 1);
  CHECK(st.open_edges == 0);
  CHECK(st.nonmanifold_vertices == 0);
  // outward: normal . (centroid - cube centre) > 0 for every face
  for (int f = 0; f < bf.rows(); ++f) {
    const Eigen::Vector3d a = m.vertices.row(bf(f, 0)), b = m.vertices.row(bf(f, 1)),
                          c = m.vertices.row(bf(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    CHECK(n.dot((a + b + c) / 3 - Eigen::Vector3d(0.5, 0.5, 0.5)) > 0);
  }
  // enclosed volume by the divergence theorem equals the tet volume sum
  double vol = 0;
  for (int f = 0; f < bf.rows(); ++f) {
    const Eigen::Vector3d a = m.vertices.row(bf(f, 0)), b = m.vertices.row(bf(f, 1)),
                          c = m.vertices.row(bf(f, 2));
    vol += a.dot(b.cross(c)) / 6;
  }
  CHECK(vol == Approx(1.0));
}

TEST_CASE("edges, incidence and components") {
  const TetMesh m = test::cube_mesh(2);
  const auto e = unique_edges(m.tets);
  const Triangles bf = boundary_faces(m.tets);
  // Euler for a ball: V - E + F - T = 1, with F all triangles
  const int V = m.num_vertices(), E = static_cast<int>(e.rows()), T = m.num_tets();
  const int F = (4 * T + static_cast<int>(bf.rows())) / 2;
  CHECK(V - E + F - T == 1);
  const Incidence inc = vertex_tet_incidence(V, m.tets);
  CHECK(inc.offset.back() == 4 * T);
  int count = 0;
  vertex_components(V, m.tets, &count);
  CHECK(count == 1);
  // two disjoint tets
  TetMesh two = test::single_tet();
  two.vertices.conservativeResize(8, 3);
  two.vertices.bottomRows(4) = two.vertices.topRows(4).array() + 5.0;
  two.tets.conservativeResize(2, 4);
  two.tets.row(1) << 4, 5, 6, 7;
  vertex_components(8, two.tets, &count);
  CHECK(count == 2);
}

TEST_CASE("surface topology detects genus and pinched vertices") {
  const TetMesh m = test::tunnel_cube();  // a cube with a tunnel: genus 1
  const SurfaceTopology st = surface_topology(m.num_vertices(), boundary_faces(m.tets));
  CHECK(st.euler == 0);
  CHECK(st.genus() == 1);
}
