// Step 5 of the initial map (vpm/initial_map.hpp): splitting the interior edges near folds
// (split_edges_near) and untangling again on the refined mesh (detail::refine_folds).
#include <catch2/catch.hpp>

#include <algorithm>
#include <set>

#include "map/initial_untangle.hpp"
#include "support/fixtures.hpp"
#include "vpm/device.hpp"
#include "vpm/geometry.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/topology.hpp"
#include "vpm/untangle.hpp"

using namespace vpm;

namespace {
std::set<std::array<int, 3>> face_set(const Triangles& f) {
  std::set<std::array<int, 3>> s;
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    std::array<int, 3> t = {f(i, 0), f(i, 1), f(i, 2)};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());  // keeps orientation
    s.insert(t);
  }
  return s;
}
}  // namespace

TEST_CASE("split_edges_near: only the tets near the seeds are split, the boundary and the volume are kept") {
  TetMesh m = test::cube_mesh(4);
  const Triangles bf = boundary_faces(m.tets);
  // a field of positions elsewhere: the midpoints must come out there too
  Points other = 2.0 * m.vertices;
  other.col(0).array() += 3.0;
  m.set_point_field("other", FieldValues(other));
  const int seed = 0;
  const SplitResult sp = split_edges_near(m, bf, {seed}, 1);
  REQUIRE(sp.inserted_vertices > 0);
  CHECK(sp.mesh.num_vertices() == m.num_vertices() + sp.inserted_vertices);
  CHECK(sp.mesh.vertices.topRows(m.num_vertices()) == m.vertices);  // input vertices first, unchanged
  CHECK(face_set(boundary_faces(sp.mesh.tets)) == face_set(bf));
  const Eigen::VectorXd v = tet_volumes(sp.mesh.vertices, sp.mesh.tets);
  CHECK(v.minCoeff() > 0);
  CHECK(v.sum() == Approx(tet_volumes(m.vertices, m.tets).sum()).epsilon(1e-12));
  const Field* f = sp.mesh.find_point_field("other");
  REQUIRE(f != nullptr);
  Points expect = 2.0 * sp.mesh.vertices;
  expect.col(0).array() += 3.0;
  CHECK((f->values - expect).cwiseAbs().maxCoeff() < 1e-12);
  // far from the seed the tets are the input's
  std::set<std::array<int, 4>> out;
  for (int t = 0; t < sp.mesh.num_tets(); ++t) out.insert({sp.mesh.tets(t, 0), sp.mesh.tets(t, 1), sp.mesh.tets(t, 2), sp.mesh.tets(t, 3)});
  int kept = 0;
  for (int t = 0; t < m.num_tets(); ++t) kept += out.count({m.tets(t, 0), m.tets(t, 1), m.tets(t, 2), m.tets(t, 3)}) > 0;
  CHECK(kept > m.num_tets() / 2);
  CHECK(kept < m.num_tets());
}

TEST_CASE("refine_folds: folds left in a ball map are untangled on a mesh refined around them") {
  TetMesh input = test::ball_mesh(5);
  const auto host = Device::host();  // held: a reference into the temporary dangled (ASan: heap-use-after-free)
  Device& dev = *host;
  InitialMapOptions opt;
  InitialMapResult res = initial_map(dev, input, opt);
  REQUIRE(inverted_tets(res.ball, res.mesh.tets).empty());
  // fold the map: an interior vertex pushed through the opposite side of its star
  int v = -1;
  for (int i = 0; i < res.mesh.num_vertices() && v < 0; ++i)
    if (!res.boundary[static_cast<size_t>(i)] && res.ball.row(i).norm() > 0.3) v = i;
  REQUIRE(v >= 0);
  const Points before = res.ball;
  res.ball.row(v) *= -1.0;
  const int folds = static_cast<int>(inverted_tets(res.ball, res.mesh.tets).size());
  REQUIRE(folds > 0);
  InitialMapReport& rep = res.report;
  rep.folds_after_untangle = folds;
  const int n0 = res.mesh.num_vertices();
  const bool refined = detail::refine_folds(dev, boundary_faces(res.mesh.tets), opt, res, rep);
  REQUIRE(rep.refine.has_value());
  CHECK(rep.refine->folds_before == folds);
  CHECK(rep.refine->folds_after == 0);
  CHECK(rep.folds_after_untangle == 0);
  CHECK(refined);
  CHECK(res.mesh.num_vertices() == n0 + rep.refine->inserted_vertices);
  REQUIRE(res.ball.rows() == res.mesh.num_vertices());
  REQUIRE(res.boundary.size() == static_cast<size_t>(res.mesh.num_vertices()));
  CHECK(inverted_tets(res.ball, res.mesh.tets).empty());
  for (int i = 0; i < res.mesh.num_vertices(); ++i)
    if (i >= n0) CHECK(!res.boundary[static_cast<size_t>(i)]);  // inserted vertices are interior
    else if (res.boundary[static_cast<size_t>(i)]) CHECK((res.ball.row(i) - before.row(i)).norm() == 0);
  CHECK(rep.refined_vertices == res.mesh.num_vertices());
  CHECK(to_json(rep).find("refine") != nullptr);
}
