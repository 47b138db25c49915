// Mesh and surface file formats: exact round trips, a corpus of broken files, the vpm binary's
// exit codes, and VTK's own reader on our .vtu output.
#include <catch2/catch.hpp>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

#include "support/fixtures.hpp"
#include "support/process.hpp"
#include "vpm/config.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"

using namespace vpm;
namespace fs = std::filesystem;

namespace {

std::string tmp(const std::string& name) { return std::string(VPM_TEST_TMP) + "/io_" + name; }
std::string bad(const std::string& name) { return std::string(VPM_TEST_DATA) + "/bad/" + name; }

using test::slurp;

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
  CHECK_THROWS_WITH(write_surface(tmp("s.ply"), TriSurface{}), Catch::Contains("unknown surface file extension"));
  TetMesh bad_field = test::single_tet();
  bad_field.point_data.push_back(Field{"short", FieldValues::Zero(2, 1), false});
  CHECK_THROWS_WITH(write_mesh(tmp("bf.vtu"), bad_field), Catch::Contains("'short'") && Catch::Contains("2 rows for 4 vertices"));
  CHECK(!fs::exists(tmp("bf.vtu")));
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
  // a tet mesh to a surface format: its boundary, outward, only the boundary's vertices
  write_mesh(tmp("cube2.vtu"), test::cube_mesh(2));
  CHECK(run_status(vpm + " convert " + tmp("cube2.vtu") + " " + tmp("cube2.off") + " --quiet") == 0);
  const TriSurface b = read_surface(tmp("cube2.off"));
  CHECK(b.vertices.rows() == 26);   // 3^3 grid points less the centre
  CHECK(b.triangles.rows() == 48);  // 6 faces x 4 squares x 2
  double volume = 0;                // divergence theorem: outward faces enclose +1
  for (Eigen::Index f = 0; f < b.triangles.rows(); ++f)
    volume += b.vertices.row(b.triangles(f, 0)).dot(b.vertices.row(b.triangles(f, 1)).cross(b.vertices.row(b.triangles(f, 2)))) / 6;
  CHECK(volume == Approx(1.0));
}

TEST_CASE("io: Medit .mesh round trip with tet references as labels") {
  const TetMesh m = mesh_with_fields();
  write_mesh(tmp("m.mesh"), m);
  const TetMesh r = read_mesh(tmp("m.mesh"));
  require_same_geometry(m, r);
  require_same_field(m.find_cell_field("label"), r.find_cell_field("label"));
  const TetMesh c = test::cube_mesh(2);
  write_mesh(tmp("c.mesh"), c);
  const TetMesh rc = read_mesh(tmp("c.mesh"));
  require_same_geometry(c, rc);
  CHECK(rc.cell_data.empty());  // all references 0: no label field
  // free-form layout, comments, skipped sections, keyword case
  spit(tmp("free.mesh"),
       "# comment\nMeshVersionFormatted\n1\nDimension\n3\nvertices 4\n0 0 0 7 1 0 0 7\n0 1 0 7 0 0 1 7\n"
       "Edges 1\n1 2 0\nCorners 2 1 2\nTETRAHEDRA\n1\n1 2 3 4 5\nTriangles 1 1 2 3 0\nEnd\n");
  const TetMesh f = read_mesh(tmp("free.mesh"));
  CHECK(f.num_vertices() == 4);
  CHECK(f.tets.row(0) == Eigen::RowVector4i(0, 1, 2, 3));
  CHECK(f.find_cell_field("label")->values(0, 0) == 5);
}

TEST_CASE("io: Gmsh .msh 4.1 round trip keeps tet order and physical tags as labels") {
  const TetMesh m = mesh_with_fields();
  write_mesh(tmp("g.msh"), m);
  const TetMesh r = read_mesh(tmp("g.msh"));
  require_same_geometry(m, r);
  require_same_field(m.find_cell_field("label"), r.find_cell_field("label"));
  const TetMesh c = test::cube_mesh(2);
  write_mesh(tmp("gc.msh"), c);
  const TetMesh rc = read_mesh(tmp("gc.msh"));
  require_same_geometry(c, rc);
  CHECK(rc.cell_data.empty());
  // Sparse, unsorted node tags; other element types ignored; unknown sections skipped.
  spit(tmp("gs.msh"),
       "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 7 \"brain\"\n$EndPhysicalNames\n"
       "$Entities\n1 0 0 1\n1 0 0 0 0\n5 0 0 0 1 1 1 1 7 0\n$EndEntities\n"
       "$Nodes\n2 4 10 40\n0 1 0 1\n40\n0 0 1\n3 5 0 3\n30\n10\n20\n0 1 0\n0 0 0\n1 0 0\n$EndNodes\n"
       "$Elements\n2 3 1 3\n0 1 15 1\n2 40\n3 5 4 2\n3 10 20 30 40\n1 40 30 20 10\n$EndElements\n");
  const TetMesh g = read_mesh(tmp("gs.msh"));
  REQUIRE(g.num_vertices() == 4);
  CHECK(g.vertices.row(0) == Eigen::RowVector3d(0, 0, 0));  // tag 10
  CHECK(g.vertices.row(3) == Eigen::RowVector3d(0, 0, 1));  // tag 40
  REQUIRE(g.num_tets() == 2);
  CHECK(g.tets.row(0) == Eigen::RowVector4i(3, 2, 1, 0));  // element tag 1 first
  CHECK(g.tets.row(1) == Eigen::RowVector4i(0, 1, 2, 3));
  CHECK(g.find_cell_field("label")->values(0, 0) == 7);
}

TEST_CASE("io: every mesh format converts to every other exactly") {
  const TetMesh m = mesh_with_fields();
  const std::vector<std::string> exts = {".vtu", ".node", ".mesh", ".msh"};
  for (const auto& a : exts)
    for (const auto& b : exts) {
      write_mesh(tmp("x1" + a), m);
      write_mesh(tmp("x2" + b), read_mesh(tmp("x1" + a)));
      const TetMesh r = read_mesh(tmp("x2" + b));
      INFO(a << " -> " << b);
      require_same_geometry(m, r);
      require_same_field(m.find_cell_field("label"), r.find_cell_field("label"));
    }
}

namespace {
TriSurface boundary_surface() {
  // The boundary of the ball mesh, with shuffled-free vertex numbering (all vertices used).
  TriSurface s;
  s.vertices.resize(5, 3);
  s.vertices << 0, 0, 0, 1.0 / 3, 0, 0, 0, 0.1, 0, 0, 0, 1e-300, -0.0, 0.7, 1e300;
  s.triangles.resize(6, 3);
  s.triangles << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 4, 1, 4, 3, 2, 3, 4;
  return s;
}
// Same triangles with the same coordinates, whatever the vertex numbering.
void require_same_surface(const TriSurface& a, const TriSurface& b) {
  REQUIRE(a.triangles.rows() == b.triangles.rows());
  CHECK(a.vertices.rows() == b.vertices.rows());
  for (Eigen::Index t = 0; t < a.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k)
      CHECK(a.vertices.row(a.triangles(t, k)) == b.vertices.row(b.triangles(t, k)));
}
}  // namespace

TEST_CASE("io: surfaces .off .obj .stl round trip exactly") {
  const TriSurface s = boundary_surface();
  for (const char* name : {"s.off", "s.obj", "s.stl"}) {
    INFO(name);
    write_surface(tmp(name), s);
    const TriSurface r = read_surface(tmp(name));
    require_same_surface(s, r);
    if (std::string(name) != "s.stl") {
      CHECK(r.vertices == s.vertices);
      CHECK(r.triangles == s.triangles);
    }
  }
  // binary STL: float coordinates, exact for float-representable input
  TriSurface f = s;
  f.vertices << 0, 0, 0, 0.25, 0, 0, 0, 0.5, 0, 0, 0, 1, -0.0, 0.75, 3;
  write_surface_stl_binary(tmp("b.stl"), f);
  CHECK(fs::file_size(tmp("b.stl")) == 84 + 50 * 6);
  require_same_surface(f, read_surface(tmp("b.stl")));
}

TEST_CASE("io: .obj polygons, slash forms, negative indices, .off polygons, STL merging") {
  spit(tmp("p.obj"),
       "mtllib x.mtl\no quad\nv 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0\nvn 0 0 1\nvt 0 0\n"
       "usemtl m\ns off\nf 1/1/1 2/1/1 3//1 4/1\nf -4 -2 -1\n");
  const TriSurface o = read_surface(tmp("p.obj"));
  REQUIRE(o.triangles.rows() == 3);
  CHECK(o.triangles.row(0) == Eigen::RowVector3i(0, 1, 2));
  CHECK(o.triangles.row(1) == Eigen::RowVector3i(0, 2, 3));
  CHECK(o.triangles.row(2) == Eigen::RowVector3i(0, 2, 3));
  spit(tmp("p.off"), "OFF 4 1 0\n# pentagon-free quad\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3 255 0 0\n");
  const TriSurface q = read_surface(tmp("p.off"));
  REQUIRE(q.triangles.rows() == 2);
  CHECK(q.triangles.row(1) == Eigen::RowVector3i(0, 2, 3));
  // STL: vertices shared by facets are merged exactly, -0 equals +0, near-equal is not merged
  spit(tmp("m.stl"),
       "solid m\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
       "endfacet\nfacet normal 0 0 1\nouter loop\nvertex -0 0 0\nvertex 0 1 0\nvertex 0.10000000000000001 0.1 0\n"
       "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\n"
       "vertex 0.10000000000000002 0.1 0\nendloop\nendfacet\nendsolid m\n");
  const TriSurface st = read_surface(tmp("m.stl"));
  CHECK(st.vertices.rows() == 5);
  CHECK(st.triangles.row(1) == Eigen::RowVector3i(0, 2, 3));
  CHECK(st.triangles.row(2) == Eigen::RowVector3i(0, 2, 4));
  // binary STL whose header starts with "solid" is still binary
  std::string bin(84 + 50, '\0');
  std::memcpy(bin.data(), "solid but binary", 16);
  const uint32_t one = 1;
  std::memcpy(bin.data() + 80, &one, 4);
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(bin.data() + 84 + 12, v, sizeof v);
  spit(tmp("sb.stl"), bin);
  const TriSurface sb = read_surface(tmp("sb.stl"));
  CHECK(sb.vertices.rows() == 3);
  CHECK(sb.vertices(1, 0) == 1.0);
}

TEST_CASE("io: .vtu from other writers: mixed cells, FieldData, Float32, attributes in any order") {
  spit(tmp("mixed.vtu"),
       "<?xml version='1.0'?>\n<!-- another writer -->\n"
       "<VTKFile byte_order='LittleEndian' type='UnstructuredGrid' version='1.0'>\n<UnstructuredGrid>\n"
       "<FieldData><DataArray type='Float64' Name='TIME' NumberOfTuples='1' format='ascii'>0.5</DataArray></FieldData>\n"
       "<Piece NumberOfCells='3' NumberOfPoints='5'>\n"
       "<PointData Scalars='s'><DataArray format='ascii' Name='s' type='Float32'>1 2 3 4 5</DataArray></PointData>\n"
       "<CellData><DataArray type='Int64' Name='region &amp; id' format='ascii'>7 8 9</DataArray></CellData>\n"
       "<Points><DataArray type='Float32' NumberOfComponents='3' format='ascii'>0 0 0 1 0 0 0 1 0 0 0 1 1 1 1</DataArray></Points>\n"
       "<Cells><DataArray type='Int32' Name='connectivity' format='ascii'>0 1 2 0 1 2 3 1 2 3 4</DataArray>\n"
       "<DataArray type='Int32' Name='offsets' format='ascii'>3 7 11</DataArray>\n"
       "<DataArray type='UInt8' Name='types' format='ascii'>5 10 10</DataArray></Cells>\n"
       "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
  const TetMesh r = read_mesh(tmp("mixed.vtu"));
  CHECK(r.num_vertices() == 5);
  REQUIRE(r.num_tets() == 2);  // the triangle (type 5) is skipped
  CHECK(r.tets.row(1) == Eigen::RowVector4i(1, 2, 3, 4));
  const Field* id = r.find_cell_field("region & id");
  REQUIRE(id);
  CHECK(id->integer);
  CHECK(id->values(0, 0) == 8);
  CHECK(id->values(1, 0) == 9);
  CHECK(!r.find_point_field("s")->integer);
}

namespace {
struct BadCase {
  const char* file;     // in tests/data/bad (read as a mesh unless a surface extension)
  const char* named;    // file the message must name ("" = the same)
  const char* where;    // ":LINE:" or ":byte N:" the message must contain ("" = none)
  const char* keyword;  // the problem
};
const BadCase kBad[] = {
    {"tetgen_text_coord.node", "", ":5:", "not a number"},
    {"tetgen_truncated.node", "", ":5:", "end of file"},
    {"tetgen_negative_count.node", "", ":1:", "negative count"},
    {"tetgen_extra_data.node", "", ":5:", "unexpected data"},
    {"tetgen_one_based.node", "tetgen_one_based.ele", ":2:", "looks 1-based"},
    {"tetgen_zero_based.ele", "", ":3:", "looks 0-based"},
    {"tetgen_huge_count.ele", "", ":1:", "more than the file"},
    {"tetgen_short_line.node", "tetgen_short_line.ele", ":3:", "expected 5"},
    {"tetgen_no_ele.node", "tetgen_no_ele.ele", "", "cannot open"},
    {"medit_zero_index.mesh", "", ":11:", "looks 0-based"},
    {"medit_truncated.mesh", "", ":7:", "end of file"},
    {"medit_unknown_keyword.mesh", "", ":9:", "unknown keyword"},
    {"medit_text.mesh", "", ":7:", "not a number"},
    {"vtu_binary.vtu", "", ":6:", "header says"},
    {"vtu_wrong_count.vtu", "", ":10:", "wrong count"},
    {"vtu_index_range.vtu", "", ":14:", "out of range"},
    {"vtu_huge_count.vtu", "", ":4:", "more than the file"},
    {"vtu_truncated.vtu", "", ":", "truncated"},
    {"msh_version2.msh", "", ":2:", "not supported"},
    {"msh_missing_node.msh", "", ":19:", "not in $Nodes"},
    {"msh_zero_tag.msh", "", ":19:", "looks 0-based"},
    {"msh_wrong_count.msh", "", ":14:", "wrong count"},
    {"off_one_based.off", "", ":8:", "looks 1-based"},
    {"off_negative.off", "", ":2:", "negative count"},
    {"off_wrong_count.off", "", ":10:", "wrong count"},
    {"obj_zero_index.obj", "", ":5:", "looks 0-based"},
    {"obj_out_of_range.obj", "", ":4:", "out of range"},
    {"obj_text.obj", "", ":2:", "not a number"},
    {"stl_truncated.stl", "", ":5:", "end of file"},
    {"stl_text.stl", "", ":6:", "not a number"},
    {"unknown_extension.xyz", "", "", "unknown"},
    {"no_such_file.vtu", "", "", "cannot open"},
};
std::string read_error(const std::string& path) {
  try {
    if (is_surface_path(path)) read_surface(path);
    else read_mesh(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}
}  // namespace

TEST_CASE("io: every broken file in tests/data/bad is an InputError naming file, line, problem") {
  for (const BadCase& c : kBad) {
    const std::string path = bad(c.file);
    const std::string named = std::string(c.named).empty() ? path : bad(c.named);
    const std::string msg = read_error(path);
    INFO(c.file << " -> " << msg);
    CHECK_THAT(msg, Catch::StartsWith(named));
    CHECK_THAT(msg, Catch::Contains(named + c.where));
    CHECK_THAT(msg, Catch::Contains(c.keyword));
    CHECK(msg.find('\n') == std::string::npos);
  }
  // every mesh/surface file of the corpus is in the table
  size_t listed = 0;
  for (const auto& e : fs::directory_iterator(std::string(VPM_TEST_DATA) + "/bad")) {
    const std::string name = e.path().filename().string();
    if (!is_mesh_path(name) && !is_surface_path(name) && name != "unknown_extension.xyz")
      continue;  // other modules' broken files (images, landmarks) share the folder
    bool found = false;
    for (const BadCase& c : kBad) found = found || name == c.file || name == c.named ||
                                          fs::path(name).stem() == fs::path(c.file).stem();
    INFO(name);
    CHECK(found);
    ++listed;
  }
  CHECK(listed >= 20);
}

TEST_CASE("io: binary STL with a wrong count reports the byte offset") {
  std::string bin(84 + 2 * 50, '\0');
  const uint32_t ten = 10;
  std::memcpy(bin.data() + 80, &ten, 4);
  spit(tmp("short.stl"), bin);
  CHECK_THROWS_WITH(read_surface(tmp("short.stl")),
                    Catch::StartsWith(tmp("short.stl") + ":byte 80:") && Catch::Contains("truncated"));
  spit(tmp("tiny.stl"), std::string(40, '\1'));
  CHECK_THROWS_WITH(read_surface(tmp("tiny.stl")), Catch::Contains("shorter than its 84-byte header"));
}

TEST_CASE("io: random corruption of valid files never crashes, only InputError") {
  // Truncations and byte flips of every format: read must either succeed or throw InputError.
  const TetMesh m = test::cube_mesh(1);
  TriSurface s;
  s.vertices = m.vertices;
  s.triangles.resize(2, 3);
  s.triangles << 0, 1, 2, 1, 2, 3;
  std::vector<std::string> files;
  for (const char* e : {".vtu", ".mesh", ".msh", ".node"}) {
    write_mesh(tmp(std::string("fz") + e), m);
    files.push_back(tmp(std::string("fz") + e));
  }
  files.push_back(tmp("fz.ele"));
  for (const char* e : {".off", ".obj", ".stl"}) {
    write_surface(tmp(std::string("fzs") + e), s);
    files.push_back(tmp(std::string("fzs") + e));
  }
  uint32_t rng = 12345;
  auto next = [&rng]() { return rng = rng * 1664525u + 1013904223u; };
  int errors = 0, reads = 0;
  for (const auto& f : files) {
    const std::string good = slurp(f);
    const std::string ext = fs::path(f).extension().string();
    for (int trial = 0; trial < 60; ++trial) {
      std::string text = good;
      if (trial % 2 == 0) {
        text.resize(next() % text.size());
      } else {
        const char junk[] = {'x', '-', '9', ' ', '\n', '/', '<', '$', '0', '#'};
        for (int k = 0; k < 3; ++k) text[next() % text.size()] = junk[next() % sizeof junk];
      }
      // write the corrupt copy next to the pair file (TetGen needs both names)
      const std::string target = tmp("fzc" + ext);
      if (ext == ".node") fs::copy_file(tmp("fz.ele"), tmp("fzc.ele"), fs::copy_options::overwrite_existing);
      if (ext == ".ele") fs::copy_file(tmp("fz.node"), tmp("fzc.node"), fs::copy_options::overwrite_existing);
      spit(target, text);
      try {
        if (is_surface_path(target)) read_surface(target);
        else read_mesh(target);
        ++reads;
      } catch (const InputError& e) {
        ++errors;
        CHECK_THAT(std::string(e.what()), Catch::StartsWith(target));
      }
    }
  }
  CHECK(errors > 100);
  INFO("reads that still succeeded: " << reads);
}

TEST_CASE("io: vpm stats prints the mesh and the map metrics, exit codes 0 and 2") {
  const std::string vpm = VPM_BINARY;
  TetMesh ball = test::ball_mesh(3);
  write_mesh(tmp("st_in.vtu"), ball);
  const std::string out = tmp("st.out"), err = tmp("st.err");
  REQUIRE(run_status(vpm + " stats " + tmp("st_in.vtu") + " > " + out + " 2> " + err) == 0);
  const std::string text = slurp(out);
  CHECK_THAT(text, Catch::Contains("vertices            64"));
  CHECK_THAT(text, Catch::Contains("tets                162"));
  CHECK_THAT(text, Catch::Contains("boundary euler      2"));
  CHECK_THAT(text, Catch::Contains("euler (V-E+F-T)     1"));
  CHECK_THAT(text, Catch::Contains("min dihedral angle"));
  // a "mapped" mesh: the same tets, vertices scaled by 2 (volume ratios stay 1 after normalising)
  TetMesh mapped = ball;
  mapped.vertices *= 2.0;
  write_mesh(tmp("st_map.msh"), mapped);
  const std::string rep = tmp("st_report.json");
  fs::remove(rep);
  REQUIRE(run_status(vpm + " stats " + tmp("st_map.msh") + " --against " + tmp("st_in.vtu") +
                     " --report " + rep + " --quiet > " + out + " 2> " + err) == 0);
  CHECK(slurp(out).empty());
  const Json j = Json::parse(slurp(rep));
  REQUIRE(j.find("device"));
  CHECK(j.find("input")->find("vertices")->number() == 64);
  CHECK(j.find("input")->find("tets")->number() == 162);
  const Json* metrics = j.find("metrics");
  REQUIRE(metrics);
  CHECK(metrics->find("inverted_tets")->number() == 0);
  CHECK(metrics->find("tet_volume_ratio")->find("max_abs_log")->number() < 1e-12);
  CHECK(metrics->find("boundary_max_radius_error")->number() == Approx(1.0).margin(1e-9));
  // different tets: exit 2, one line naming the file
  TetMesh other = mapped;
  std::swap(other.tets(5, 0), other.tets(7, 0));
  write_mesh(tmp("st_other.vtu"), other);
  CHECK(run_status(vpm + " stats " + tmp("st_other.vtu") + " --against " + tmp("st_in.vtu") + " 2> " + err) == 2);
  const std::string msg = slurp(err);
  CHECK(std::count(msg.begin(), msg.end(), '\n') == 1);
  CHECK_THAT(msg, Catch::Contains(tmp("st_other.vtu")) && Catch::Contains("tet 5"));
  // a bad file: exit 2 with the reader's message
  CHECK(run_status(vpm + " stats " + bad("medit_zero_index.mesh") + " 2> " + err) == 2);
  CHECK_THAT(slurp(err), Catch::Contains(bad("medit_zero_index.mesh") + ":11:"));
  CHECK(run_status(vpm + " stats 2> " + err) == 2);
  CHECK_THAT(slurp(err), Catch::Contains("usage"));
}

TEST_CASE("io: our .vtu opens in VTK's own reader (scripts/check_vtu.py)") {
  std::string python;
  for (const char* p : {"/usr/bin/python3", "python3"})
    if (python.empty() && run_status(std::string(p) + " -c \"import vtk\" > /dev/null 2>&1") == 0) python = p;
  if (python.empty()) {
    WARN("python3 with vtk (python3-vtk9) not available: skipping the VTK reader check");
    return;
  }
  const std::string script = std::string(VPM_SOURCE_DIR) + "/scripts/check_vtu.py";
  const std::string out = tmp("vtk.out");
  for (const VtuEncoding encoding : {VtuEncoding::binary, VtuEncoding::ascii}) {
    INFO((encoding == VtuEncoding::binary ? "binary" : "ascii"));
    write_mesh(tmp("vtk.vtu"), mesh_with_fields(), encoding);
    CHECK(run_status(python + " " + script + " " + tmp("vtk.vtu") +
                     " original_position vertex_volume_ratio label tet_volume_ratio > " + out + " 2>&1") == 0);
    const std::string text = slurp(out);
    CHECK_THAT(text, Catch::Contains("points 64"));
    CHECK_THAT(text, Catch::Contains("cells 162 types [10]"));
    CHECK_THAT(text, Catch::Contains("point field original_position components 3 type double"));
    CHECK_THAT(text, Catch::Contains("cell field label components 1 type int"));
  }
  CHECK(run_status(python + " " + script + " " + tmp("vtk.vtu") + " no_such_field > " + out + " 2>&1") == 1);
  CHECK(run_status(python + " " + script + " " + bad("vtu_truncated.vtu") + " > " + out + " 2>&1") == 1);
}

TEST_CASE("io: large ASCII .vtu arrays (read on the host threads) round trip exactly and name a bad token's line") {
  // cube_mesh(24): 15,625 vertices (46,875 coordinates) and 82,944 tets (331,776 connectivity
  // values), so the connectivity, offsets and types and a wide point field take the threaded path
  TetMesh m = test::cube_mesh(24);
  FieldValues wide(m.num_vertices(), 6);
  for (int i = 0; i < m.num_vertices(); ++i)
    for (int c = 0; c < 6; ++c) wide(i, c) = std::sin(0.37 * i + c) * std::pow(10.0, (i % 9) - 4);
  m.set_point_field("wide", wide);
  const std::string path = tmp("large.vtu");
  write_mesh(path, m, VtuEncoding::ascii);
  const TetMesh r = read_mesh(path);
  require_same_geometry(m, r);
  require_same_field(m.find_point_field("wide"), r.find_point_field("wide"));
  // a bad token in the middle of the connectivity: the message names its line, as the
  // sequential reader does
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const size_t conn = s.find("Name=\"connectivity\"");
  REQUIRE(conn != std::string::npos);
  size_t at = conn;
  for (int lines = 0; lines < 40000; ++lines) at = s.find('\n', at + 1);
  const size_t line = static_cast<size_t>(std::count(s.begin(), s.begin() + static_cast<long>(at) + 1, '\n')) + 1;
  s.insert(at + 1, "x7 ");
  const std::string bad_path = tmp("large_bad.vtu");
  std::ofstream(bad_path) << s;
  const std::string msg = read_error(bad_path);
  INFO(msg);
  CHECK_THAT(msg, Catch::Contains(bad_path + ":" + std::to_string(line) + ":"));
  CHECK_THAT(msg, Catch::Contains("x7"));
}
