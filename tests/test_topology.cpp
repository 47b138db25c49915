#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <random>

#include "support/fixtures.hpp"
#include "mesh/tet_grid.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/labels.hpp"
#include "vpm/locate.hpp"
#include "vpm/mesh_order.hpp"
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

TEST_CASE("sort_spatially: a permutation that keeps every tet, its orientation and the fields, and brings neighbours together") {
  // a ball mesh numbered at random, as a mesher may leave it
  const TetMesh ball = test::ball_mesh(8);
  const int n = ball.num_vertices(), m = ball.num_tets();
  std::vector<int> shuffle(static_cast<size_t>(n));
  std::iota(shuffle.begin(), shuffle.end(), 0);
  std::mt19937 rng(5);
  std::shuffle(shuffle.begin(), shuffle.end(), rng);  // shuffle[new] = ball's index
  std::vector<int> inverse(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) inverse[static_cast<size_t>(shuffle[static_cast<size_t>(i)])] = i;
  TetMesh mixed;
  mixed.vertices.resize(n, 3);
  for (int i = 0; i < n; ++i) mixed.vertices.row(i) = ball.vertices.row(shuffle[static_cast<size_t>(i)]);
  mixed.tets.resize(m, 4);
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) mixed.tets(t, k) = inverse[static_cast<size_t>(ball.tets(t, k))];
  FieldValues id(n, 1), tid(m, 1);
  for (int i = 0; i < n; ++i) id(i, 0) = i;
  for (int t = 0; t < m; ++t) tid(t, 0) = t;
  mixed.set_point_field("id", id, true);
  mixed.set_cell_field("tid", tid, true);
  auto spread = [](const TetMesh& mesh) {  // median over tets of max - min vertex index
    std::vector<int> s;
    for (int t = 0; t < mesh.num_tets(); ++t) s.push_back(mesh.tets.row(t).maxCoeff() - mesh.tets.row(t).minCoeff());
    std::nth_element(s.begin(), s.begin() + s.size() / 2, s.end());
    return s[s.size() / 2];
  };

  TetMesh sorted = mixed;
  const std::vector<int> old_of_new = sort_spatially(sorted);
  REQUIRE(sorted.num_vertices() == n);
  REQUIRE(sorted.num_tets() == m);
  std::vector<int> seen(static_cast<size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    const int o = old_of_new[static_cast<size_t>(i)];
    ++seen[static_cast<size_t>(o)];
    CHECK(sorted.vertices.row(i) == mixed.vertices.row(o));
    CHECK(sorted.find_point_field("id")->values(i, 0) == o);
  }
  CHECK(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; }));
  std::vector<int> tet_seen(static_cast<size_t>(m), 0);
  for (int t = 0; t < m; ++t) {
    const int o = static_cast<int>(sorted.find_cell_field("tid")->values(t, 0));
    ++tet_seen[static_cast<size_t>(o)];
    for (int k = 0; k < 4; ++k) CHECK(old_of_new[static_cast<size_t>(sorted.tets(t, k))] == mixed.tets(o, k));
  }
  CHECK(std::all_of(tet_seen.begin(), tet_seen.end(), [](int c) { return c == 1; }));
  CHECK(tet_volumes(sorted.vertices, sorted.tets).minCoeff() > 0);
  INFO("index spread per tet: random " << spread(mixed) << ", sorted " << spread(sorted));
  CHECK(spread(sorted) < 0.2 * spread(mixed));
}

TEST_CASE("face matching (boundary faces, non-manifold faces, face neighbours) agrees with a map of sorted triples") {
  // a ball numbered at random (scattered vertex lists, more vertices than one thread's share),
  // plus one tet glued onto an interior face: that face is then shared by three tets
  TetMesh mesh = test::ball_mesh(20);
  const int n0 = mesh.num_vertices();
  REQUIRE(n0 > 8192);
  std::vector<int> perm(static_cast<size_t>(n0));
  std::iota(perm.begin(), perm.end(), 0);
  std::mt19937 rng(11);
  std::shuffle(perm.begin(), perm.end(), rng);
  const Points original = mesh.vertices;
  for (int i = 0; i < n0; ++i) mesh.vertices.row(perm[static_cast<size_t>(i)]) = original.row(i);
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (int k = 0; k < 4; ++k) mesh.tets(t, k) = perm[static_cast<size_t>(mesh.tets(t, k))];
  const int m0 = mesh.num_tets();
  mesh.tets.conservativeResize(m0 + 1, 4);
  mesh.tets.row(m0) << mesh.tets(m0 / 2, 1), mesh.tets(m0 / 2, 2), mesh.tets(m0 / 2, 3), n0;  // vertex n0: new
  const int m = mesh.num_tets();

  std::map<std::array<int, 3>, std::vector<int>> faces;  // sorted triple -> slots 4 t + k (k: opposite corner)
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> f;
      int j = 0;
      for (int c = 0; c < 4; ++c)
        if (c != k) f[static_cast<size_t>(j++)] = mesh.tets(t, c);
      std::sort(f.begin(), f.end());
      faces[f].push_back(4 * t + k);
    }
  int boundary = 0, shared3 = 0;
  for (const auto& [f, slots] : faces) {
    boundary += slots.size() == 1;
    shared3 += slots.size() > 2;
  }
  CHECK(shared3 == 1);
  CHECK(nonmanifold_faces(mesh.tets) == 1);

  std::vector<int> owner;
  const Triangles bf = boundary_faces(mesh.tets, &owner);
  REQUIRE(bf.rows() == boundary);
  std::array<int, 3> last{-1, -1, -1};
  for (int i = 0; i < bf.rows(); ++i) {
    std::array<int, 3> f = {bf(i, 0), bf(i, 1), bf(i, 2)};
    std::sort(f.begin(), f.end());
    const auto it = faces.find(f);
    REQUIRE(it != faces.end());
    REQUIRE(it->second.size() == 1);
    CHECK(it->second[0] / 4 == owner[static_cast<size_t>(i)]);
    CHECK(last < f);  // in increasing order of the sorted triple
    last = f;
    // oriented as the owner's face: the opposite corner on the negative side
    const int t = owner[static_cast<size_t>(i)], k = it->second[0] % 4;
    if (t != m0) {  // the glued tet has no orientation to check (nor a position for its new vertex n0)
      const Eigen::Vector3d a = mesh.vertices.row(bf(i, 0)), b = mesh.vertices.row(bf(i, 1)), c = mesh.vertices.row(bf(i, 2));
      const Eigen::Vector3d o = mesh.vertices.row(mesh.tets(t, k));
      CHECK((b - a).cross(c - a).dot(o - a) < 0);
    }
  }

  const std::vector<int> nbr = detail::tet_neighbors(mesh.tets);
  for (const auto& [f, slots] : faces) {
    if (slots.size() == 2) {
      CHECK(nbr[static_cast<size_t>(slots[0])] == slots[1] / 4);
      CHECK(nbr[static_cast<size_t>(slots[1])] == slots[0] / 4);
    } else {
      for (int s : slots) CHECK(nbr[static_cast<size_t>(s)] == -1);
    }
  }
}

TEST_CASE("tet_topology: the faces sorted once give what each query gives, and a locator built on it locates the same") {
  TetMesh m = test::ball_mesh(5);
  std::mt19937 gen(9);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02), u(-1.05, 1.05);
  for (Eigen::Index v = 0; v < m.vertices.rows(); ++v)  // a moved embedding of the same tets
    m.vertices.row(v) += Eigen::RowVector3d(jitter(gen), jitter(gen), jitter(gen));
  const TetTopology t = tet_topology(m.num_vertices(), m.tets);
  CHECK(t.boundary == boundary_faces(m.tets));
  CHECK(t.boundary_vertex == boundary_vertex_mask(m.num_vertices(), boundary_faces(m.tets)));
  CHECK(t.neighbours == detail::tet_neighbors(m.tets));
  CHECK(std::count(t.neighbours.begin(), t.neighbours.end(), -1) == t.boundary.rows());
  Points p(500, 3);
  for (Eigen::Index i = 0; i < p.rows(); ++i) p.row(i) << u(gen), u(gen), u(gen);
  const std::vector<Location> a = TetLocator(m.vertices, m.tets).locate_all(p),
                              b = TetLocator(m.vertices, m.tets, t).locate_all(p);
  int differ = 0, inside = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    differ += a[i].tet != b[i].tet || a[i].min_bary != b[i].min_bary;
    inside += a[i].inside();
  }
  CHECK(differ == 0);
  CHECK(inside > 100);
  // labels and pull-backs through a prepared locator equal those of the one-off calls
  std::vector<int> labels(static_cast<size_t>(m.tets.rows()));
  for (size_t k = 0; k < labels.size(); ++k) labels[k] = static_cast<int>(k % 7);
  const TetLocator at(m.vertices, m.tets, t);
  CHECK(sample_labels(at, labels, p) == sample_labels(m.vertices, m.tets, labels, p));
  const Points native = 2.0 * m.vertices;
  CHECK(pull_back_points(p, at, native) == pull_back_points(p, m.vertices, m.tets, native));
  // a topology of another mesh is refused
  const TetMesh small = test::ball_mesh(2);
  CHECK_THROWS_AS(TetLocator(m.vertices, m.tets, tet_topology(small.num_vertices(), small.tets)), InputError);
  CHECK_THROWS_AS(tet_topology(4, small.tets), InputError);
}
