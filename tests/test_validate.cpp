#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "support/fixtures.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/validate.hpp"

using namespace vpm;
using Catch::Matchers::Contains;

namespace {
std::string error_of(TetMesh m, ValidateOptions o = {}) {
  try {
    validate_mesh(m, "in.mesh", o);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("a good cube mesh validates and reports its boundary") {
  TetMesh m = test::cube_mesh(3);
  const ValidationReport r = validate_mesh(m, "cube");
  CHECK(r.reoriented_tets == 0);
  CHECK(r.boundary_euler == 2);
  CHECK(r.boundary_faces == 108);
  CHECK(r.min_dihedral_deg == Approx(45.0).margin(1e-9));
  CHECK(r.sliver_tets == 0);
}

TEST_CASE("slivers are counted: tets with a dihedral angle below kSliverDihedralDeg") {
  TetMesh m = test::single_tet();
  m.vertices.row(3) << 0.3, 0.3, 0.005;  // the apex almost in the base plane
  const ValidationReport r = validate_mesh(m, "sliver");
  CHECK(r.min_dihedral_deg < kSliverDihedralDeg);
  CHECK(r.sliver_tets == 1);
  TetMesh fine = test::single_tet();
  CHECK(validate_mesh(fine, "tet").sliver_tets == 0);
}

TEST_CASE("negatively oriented tets are fixed and counted") {
  TetMesh m = test::cube_mesh(2);
  for (int t = 0; t < m.num_tets(); t += 3) std::swap(m.tets(t, 0), m.tets(t, 1));
  const ValidationReport r = validate_mesh(m, "cube");
  CHECK(r.reoriented_tets == (m.num_tets() + 2) / 3);
  CHECK(tet_volumes(m.vertices, m.tets).minCoeff() > 0);
  REQUIRE(r.notes.size() == 1);
  CHECK_THAT(r.notes[0], Contains("reoriented"));
}

TEST_CASE("each invalid mesh is refused with a precise message") {
  const TetMesh good = test::cube_mesh(2);
  SECTION("index out of range") {
    TetMesh m = good;
    m.tets(5, 2) = 1000;
    CHECK_THAT(error_of(m), Contains("in.mesh: tet 5") && Contains("out of range"));
  }
  SECTION("negative index") {
    TetMesh m = good;
    m.tets(0, 0) = -1;
    CHECK_THAT(error_of(m), Contains("tet 0") && Contains("out of range"));
  }
  SECTION("non-finite coordinate") {
    TetMesh m = good;
    m.vertices(4, 1) = std::numeric_limits<double>::quiet_NaN();
    CHECK_THAT(error_of(m), Contains("vertex 4") && Contains("not finite"));
  }
  SECTION("repeated vertex in a tet") {
    TetMesh m = good;
    m.tets(3, 1) = m.tets(3, 0);
    CHECK_THAT(error_of(m), Contains("tet 3") && Contains("degenerate"));
  }
  SECTION("flat tet") {
    TetMesh m = test::single_tet();
    m.vertices(3, 2) = 0;  // all four points in z = 0
    CHECK_THAT(error_of(m), Contains("zero volume"));
  }
  SECTION("duplicate tet") {
    TetMesh m = good;
    m.tets.conservativeResize(m.num_tets() + 1, 4);
    m.tets.row(m.num_tets() - 1) = m.tets.row(7);
    CHECK_THAT(error_of(m), Contains("duplicate of tet 7"));
  }
  SECTION("isolated vertex") {
    TetMesh m = good;
    m.vertices.conservativeResize(m.num_vertices() + 1, 3);
    m.vertices.row(m.num_vertices() - 1) << 9, 9, 9;
    CHECK_THAT(error_of(m), Contains("isolated"));
  }
  SECTION("two components") {
    TetMesh m = test::single_tet();
    m.vertices.conservativeResize(8, 3);
    m.vertices.bottomRows(4) = m.vertices.topRows(4).array() + 3.0;
    m.tets.conservativeResize(2, 4);
    m.tets.row(1) << 4, 5, 6, 7;
    CHECK_THAT(error_of(m), Contains("2 connected components"));
  }
  SECTION("two tets sharing only a vertex pinch the boundary") {
    TetMesh m = test::single_tet();
    m.vertices.conservativeResize(7, 3);
    m.vertices.row(4) << -1, 0, 0;
    m.vertices.row(5) << 0, -1, 0;
    m.vertices.row(6) << 0, 0, -1;
    m.tets.conservativeResize(2, 4);
    m.tets.row(1) << 0, 4, 6, 5;
    CHECK_THAT(error_of(m), Contains("non-manifold boundary"));
  }
  SECTION("a face shared by three tets") {
    TetMesh m = test::single_tet();
    m.vertices.conservativeResize(6, 3);
    m.vertices.row(4) << 0.2, 0.2, -1;
    m.vertices.row(5) << 0.3, 0.3, -2;
    m.tets.conservativeResize(3, 4);
    m.tets.row(1) << 0, 2, 1, 4;
    m.tets.row(2) << 0, 2, 1, 5;
    CHECK_THAT(error_of(m), Contains("shared by more than two tets"));
  }
  SECTION("genus one boundary") {
    TetMesh m = test::tunnel_cube();
    CHECK_THAT(error_of(m), Contains("Euler characteristic 0") && Contains("genus 1"));
    ValidateOptions relaxed;
    relaxed.require_ball_topology = false;
    CHECK(error_of(m, relaxed).empty());
  }
  SECTION("empty mesh") {
    TetMesh m;
    CHECK_THAT(error_of(m), Contains("no vertices"));
  }
}
