// Mesh and surface file formats: exact round trips, a corpus of broken files, the vpm binary's
// exit codes, and VTK's own reader on our .vtu output.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

#include "support/fixtures.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"

using namespace vpm;
namespace fs = std::filesystem;

namespace {

std::string tmp(const std::string& name) { return std::string(VPM_TEST_TMP) + "/io_" + name; }
std::string bad(const std::string& name) { return std::string(VPM_TEST_DATA) + "/bad/" + name; }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void spit(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// A ball mesh with the fields `map` writes: original_position (3), vertex_volume_ratio,
// label (int) on points and tet_volume_ratio, label (int) on cells.
TetMesh mesh_with_fields() {
  TetMesh m = test::ball_mesh(3);
  const int n = m.num_vertices(), t = m.num_tets();
  FieldValues orig = m.vertices * 1.0 / 3.0;  // non-terminating decimals
  m.set_point_field("original_position", orig);
  FieldValues vr(n, 1), lp(n, 1), tr(t, 1), lc(t, 1);
  for (int i = 0; i < n; ++i) {
    vr(i, 0) = std::exp(0.1 * std::sin(i * 1.7)) * (1 + 1e-16 * i);
    lp(i, 0) = i % 5 - 2;
  }
  for (int i = 0; i < t; ++i) {
    tr(i, 0) = 1.0 / (3.0 + i);
    lc(i, 0) = 1 + i % 3;
  }
  m.set_point_field("vertex_volume_ratio", vr);
  m.set_point_field("label", lp, true);
  m.set_cell_field("tet_volume_ratio", tr);
  m.set_cell_field("label", lc, true);
  return m;
}

void require_same_geometry(const TetMesh& a, const TetMesh& b) {
  REQUIRE(a.vertices.rows() == b.vertices.rows());
  REQUIRE(a.tets.rows() == b.tets.rows());
  CHECK(a.vertices == b.vertices);  // exact: written with round-trip precision
  CHECK(a.tets == b.tets);
}

void require_same_field(const Field* a, const Field* b) {
  REQUIRE(a != nullptr);
  REQUIRE(b != nullptr);
  CHECK(a->integer == b->integer);
  REQUIRE(a->values.rows() == b->values.rows());
  REQUIRE(a->values.cols() == b->values.cols());
  CHECK(a->values == b->values);
}

// Exit status of a shell command.
int run_status(const std::string& cmd) {
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

}  // namespace

TEST_CASE("io: .vtu round trip keeps geometry and every field exactly") {
  const TetMesh m = mesh_with_fields();
  const std::string path = tmp("fields.vtu");
  write_mesh(path, m);
  const TetMesh r = read_mesh(path);
  require_same_geometry(m, r);
  REQUIRE(r.point_data.size() == m.point_data.size());
  REQUIRE(r.cell_data.size() == m.cell_data.size());
  for (const auto& f : m.point_data) require_same_field(&f, r.find_point_field(f.name));
  for (const auto& f : m.cell_data) require_same_field(&f, r.find_cell_field(f.name));
  CHECK(r.find_point_field("original_position")->values.cols() == 3);
}

TEST_CASE("io: TetGen .node/.ele round trip, either name, with labels and .face") {
  const TetMesh m = mesh_with_fields();
  write_mesh(tmp("tg.node"), m);
  CHECK(fs::exists(tmp("tg.ele")));
  CHECK(fs::exists(tmp("tg.face")));
  for (const char* name : {"tg.node", "tg.ele"}) {
    const TetMesh r = read_mesh(tmp(name));
    require_same_geometry(m, r);
    require_same_field(m.find_cell_field("label"), r.find_cell_field("label"));
    CHECK(r.point_data.empty());
  }
  // without labels: no region column, no label field
  const TetMesh c = test::cube_mesh(2);
  write_mesh(tmp("tg2.ele"), c);
  const TetMesh r = read_mesh(tmp("tg2.node"));
  require_same_geometry(c, r);
  CHECK(r.cell_data.empty());
}

TEST_CASE("io: TetGen numbering from 0 or 1, attributes, markers, comments, 10-node tets") {
  spit(tmp("z.node"),
       "# four points, numbered from 0, one attribute, boundary markers\n"
       "4 3 1 1\n"
       "0 0 0 0  7.5 1\n"
       "1 1 0 0  7.5 1   # trailing comment\n"
       "\n"
       "2 0 1 0  7.5 1\n"
       "3 0 0 1  7.5 1\n");
  spit(tmp("z.ele"), "1 10 1\n0  0 1 2 3  4 5 6 7 8 9  -3\n");
  TetMesh r = read_mesh(tmp("z.node"));
  CHECK(r.num_vertices() == 4);
  CHECK(r.tets.row(0) == Eigen::RowVector4i(0, 1, 2, 3));
  CHECK(r.find_cell_field("label")->values(0, 0) == -3);
  CHECK(r.find_cell_field("label")->integer);
  spit(tmp("o.node"), "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n");
  spit(tmp("o.ele"), "1 4 0\n1 4 3 2 1\n");
  r = read_mesh(tmp("o.ele"));
  CHECK(r.tets.row(0) == Eigen::RowVector4i(3, 2, 1, 0));
  CHECK(r.vertices(1, 0) == 1.0);
}

TEST_CASE("io: unknown extensions and missing files are InputErrors naming the path") {
  CHECK_THROWS_WITH(read_mesh(tmp("x.xyz")), Catch::Contains("x.xyz") && Catch::Contains("unknown"));
  CHECK_THROWS_WITH(read_mesh(tmp("missing.vtu")), Catch::Contains("missing.vtu") && Catch::Contains("cannot open"));
  CHECK_THROWS_AS(write_mesh(tmp("x.abc"), test::single_tet()), InputError);
  CHECK_THROWS_WITH(write_mesh(std::string(VPM_TEST_TMP) + "/no/such/dir/a.vtu", test::single_tet()),
                    Catch::Contains("does not exist"));
  CHECK(is_mesh_path("A.VTU"));
  CHECK(is_mesh_path("a.node"));
  CHECK(!is_mesh_path("a.off"));
  CHECK(is_surface_path("a.STL"));
}

TEST_CASE("io: vpm convert and exit codes") {
  const std::string vpm = VPM_BINARY;
  write_mesh(tmp("cv.vtu"), mesh_with_fields());
  CHECK(run_status(vpm + " convert " + tmp("cv.vtu") + " " + tmp("cv.ele") + " --quiet") == 0);
  require_same_geometry(read_mesh(tmp("cv.vtu")), read_mesh(tmp("cv.node")));
  const std::string err = tmp("cv.err");
  spit(tmp("cvbad.node"), "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 zero 1 0\n4 0 0 1\n");
  spit(tmp("cvbad.ele"), "1 4 0\n1 1 2 3 4\n");
  CHECK(run_status(vpm + " convert " + tmp("cvbad.node") + " " + tmp("cvbad.vtu") + " 2> " + err) == 2);
  const std::string msg = slurp(err);
  CHECK(std::count(msg.begin(), msg.end(), '\n') == 1);
  CHECK_THAT(msg, Catch::Contains(tmp("cvbad.node") + ":4:") && Catch::Contains("not a number"));
  CHECK(!fs::exists(tmp("cvbad.vtu")));
}
