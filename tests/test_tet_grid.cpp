// The point-location grid (mesh/tet_grid.hpp) and the vertex-tet incidence, built in chunks on
// several threads, and the face table: the grid must list in every cell exactly the tets whose
// grown bounding box overlaps it, in ascending order (the order the location's fallback search
// and its device twin rely on for identical maps).
#include <catch2/catch.hpp>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "mesh/face_table.hpp"
#include "mesh/tet_geometry.hpp"
#include "mesh/tet_grid.hpp"
#include "vpm/topology.hpp"
#include "support/shapes.hpp"

using namespace vpm;

namespace {
/// The tets in a seeded random order.
Tets shuffled_tets(const Tets& tets, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<int> perm(static_cast<size_t>(tets.rows()));
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  Tets out(tets.rows(), 4);
  for (Eigen::Index t = 0; t < tets.rows(); ++t) out.row(t) = tets.row(perm[static_cast<size_t>(t)]);
  return out;
}
}  // namespace

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
  const Tets shuffled = shuffled_tets(mesh.tets, 11);
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

TEST_CASE("face table: every slot, ordered by (sorted triple, slot), grouped by smallest vertex") {
  TetMesh mesh = test::box_mesh(26, 24, 22);
  const Tets shuffled = shuffled_tets(mesh.tets, 11);
  const detail::FaceTable ft = detail::face_table(shuffled);
  // the serial reference: all (triple, slot) pairs sorted
  constexpr int kOpp[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::vector<std::pair<std::array<int, 3>, int>> ref;
  for (int t = 0; t < shuffled.rows(); ++t)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> s = {shuffled(t, kOpp[k][0]), shuffled(t, kOpp[k][1]), shuffled(t, kOpp[k][2])};
      std::sort(s.begin(), s.end());
      ref.push_back({s, 4 * t + k});
    }
  std::sort(ref.begin(), ref.end());
  REQUIRE(ft.entries.size() == ref.size());
  REQUIRE(ft.start.size() == static_cast<size_t>(mesh.num_vertices()) + 1);
  size_t wrong = 0;
  for (size_t i = 0; i < ref.size(); ++i) {
    const auto& [s, slot] = ref[i];
    const std::uint64_t rest = (static_cast<std::uint64_t>(s[1]) << 32) | static_cast<std::uint32_t>(s[2]);
    wrong += ft.entries[i].slot != slot || ft.entries[i].rest != rest ||
             static_cast<int>(i) < ft.start[static_cast<size_t>(s[0])] ||
             static_cast<int>(i) >= ft.start[static_cast<size_t>(s[0]) + 1];
  }
  CHECK(wrong == 0);
  int pairs = 0, singles = 0;  // interior faces twice, boundary faces once
  ft.for_each_group([&](int, int count) { (count == 2 ? pairs : singles) += 1; });
  CHECK(2 * pairs + singles == static_cast<int>(ref.size()));
  CHECK(singles == static_cast<int>(boundary_faces(mesh.tets).rows()));
}

TEST_CASE("tet geometry (kernels/tet_geometry.clh) on the host: Eigen's volume and 3x3 inverse, bit for bit") {
  // The header's host branch replaced Eigen's e1.dot(e2.cross(e3)) / 6 and M.inverse() in
  // geometry.cpp and tet_grid.cpp; maps stay byte for byte the same only while these agree
  // exactly (the volume map is not stable at round-off: 1e-16 becomes 1e-4 after the polish).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    double e[3][3];
    Eigen::Matrix3d M;
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) M(c, k) = e[k][c] = u(rng) * (trial % 2 ? 1e-3 : 1.0);
    if (std::abs(M.determinant()) < 1e-12) continue;
    const Eigen::Vector3d e1 = M.col(0), e2 = M.col(1), e3 = M.col(2);
    REQUIRE(detail::tg_volume(e[0], e[1], e[2]) == e1.dot(e2.cross(e3)) / 6.0);
    double q[9];
    detail::tg_inverse_rows(e[0], e[1], e[2], q);
    const Eigen::Matrix3d Mi = M.inverse();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) REQUIRE(q[3 * r + c] == Mi(r, c));
    REQUIRE(detail::tg_length(e[0]) == e1.norm());
    ++checked;
  }
  CHECK(checked > 1900);
  // and the rows are M^-1's: M^-1 M = I
  Points x(4, 3);
  x << 0, 0, 0, 1, 0.1, 0, 0.2, 1, 0, 0.1, 0.3, 1;
  Tets t(1, 4);
  t << 0, 1, 2, 3;
  double e[3][3], q[9];
  detail::tet_edges(x, t, 0, e);
  detail::tg_inverse_rows(e[0], e[1], e[2], q);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      CHECK(q[3 * r] * e[c][0] + q[3 * r + 1] * e[c][1] + q[3 * r + 2] * e[c][2] == Approx(r == c ? 1.0 : 0.0).margin(1e-14));
}
