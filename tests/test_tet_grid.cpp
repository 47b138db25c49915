// The point-location grid (mesh/tet_grid.hpp): built in tet chunks on several threads, it must
// list in every cell exactly the tets whose grown bounding box overlaps it, in ascending order
// (the order the location's fallback search and its device twin rely on for identical maps).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "mesh/tet_grid.hpp"
#include "vpm/topology.hpp"
#include "support/shapes.hpp"

using namespace vpm;

TEST_CASE("tet grid: each cell lists the tets overlapping it in ascending order, as one serial pass") {
  TetMesh mesh = test::box_mesh(26, 24, 22);  // > 65,536 tets: the chunked (threaded) build
  REQUIRE(mesh.num_tets() > 65536);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  for (Eigen::Index i = 0; i < mesh.vertices.rows(); ++i)
    for (int c = 0; c < 3; ++c) mesh.vertices(i, c) += jitter(rng) / 26.0;
  const std::vector<int> nbr = detail::tet_neighbors(mesh.tets);
  detail::TetGrid g;
  detail::build_background(g, mesh.vertices, mesh.tets, nbr);
  const int gx = g.dims[0], gy = g.dims[1], gz = g.dims[2];
  const size_t cells = static_cast<size_t>(gx) * gy * gz;
  REQUIRE(g.cell_start.size() == cells + 1);

  // the serial reference: the same cell ranges, tets appended in ascending order
  std::vector<std::vector<int>> ref(cells);
  const double h = 1.0 / g.inv_h;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    int a[3], b[3];
    for (int c = 0; c < 3; ++c) {
      double mn = 1e300, mx = -1e300;
      for (int k = 0; k < 4; ++k) {
        mn = std::min(mn, mesh.vertices(mesh.tets(t, k), c));
        mx = std::max(mx, mesh.vertices(mesh.tets(t, k), c));
      }
      a[c] = std::clamp(static_cast<int>(std::floor((mn - 0.25 * h - g.lo[c]) * g.inv_h)), 0, g.dims[c] - 1);
      b[c] = std::clamp(static_cast<int>(std::floor((mx + 0.25 * h - g.lo[c]) * g.inv_h)), 0, g.dims[c] - 1);
    }
    for (int k = a[2]; k <= b[2]; ++k)
      for (int j = a[1]; j <= b[1]; ++j)
        for (int i = a[0]; i <= b[0]; ++i) ref[i + gx * (j + static_cast<size_t>(gy) * k)].push_back(t);
  }
  size_t mismatched = 0, total = 0;
  for (size_t cell = 0; cell < cells; ++cell) {
    const std::vector<int> got(g.cell_tets.begin() + g.cell_start[cell], g.cell_tets.begin() + g.cell_start[cell + 1]);
    mismatched += got != ref[cell];
    total += ref[cell].size();
  }
  CHECK(mismatched == 0);
  CHECK(g.cell_tets.size() == total);
  CHECK(total > static_cast<size_t>(mesh.num_tets()));  // tets straddle cells: the lists overlap
}

TEST_CASE("vertex-tet incidence built in tet chunks lists each vertex's tets in ascending order") {
  TetMesh mesh = test::box_mesh(26, 24, 22);  // > 65,536 tets: the chunked (threaded) build
  REQUIRE(mesh.num_tets() > 65536);
  // tets in a random order, so chunk boundaries cut through every vertex's list
  std::mt19937 rng(11);
  std::vector<int> perm(static_cast<size_t>(mesh.num_tets()));
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  Tets shuffled(mesh.num_tets(), 4);
  for (int t = 0; t < mesh.num_tets(); ++t) shuffled.row(t) = mesh.tets.row(perm[static_cast<size_t>(t)]);
  const int n = mesh.num_vertices();
  const Incidence inc = vertex_tet_incidence(n, shuffled);
  std::vector<std::vector<int>> ref(static_cast<size_t>(n));
  for (int t = 0; t < shuffled.rows(); ++t)
    for (int c = 0; c < 4; ++c) ref[static_cast<size_t>(shuffled(t, c))].push_back(t);
  REQUIRE(inc.offset.size() == static_cast<size_t>(n) + 1);
  REQUIRE(inc.offset.back() == 4 * shuffled.rows());
  int wrong = 0;
  for (int v = 0; v < n; ++v) {
    const std::vector<int> got(inc.tet_of.begin() + inc.offset[v], inc.tet_of.begin() + inc.offset[v + 1]);
    wrong += got != ref[static_cast<size_t>(v)];
  }
  CHECK(wrong == 0);
}
