// .vtu files as VTK and ParaView write them (host/io/vtk_binary.hpp): inline base64, appended raw
// and base64, zlib blocks, UInt32 and UInt64 headers, <InformationKey> children; fixtures written
// by VTK's own writer (tests/data/vtk/make_fixtures.py). Every one reads exactly as the ASCII
// one; corrupt copies give an InputError naming the file, never a crash.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <sstream>

#include "vpm/error.hpp"
#include "vpm/io.hpp"

using namespace vpm;
namespace fs = std::filesystem;

namespace {

std::string fixture(const std::string& name) { return std::string(VPM_TEST_DATA) + "/vtk/grid_" + name + ".vtu"; }

const char* kEncodings[] = {"binary", "binary_u64", "binary_zlib", "appended_raw", "appended_raw_zlib_u64",
                            "appended_base64", "appended_base64_zlib"};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void spit(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

}  // namespace

TEST_CASE("io: .vtu in every binary form VTK writes reads exactly as its ASCII twin") {
  const TetMesh ref = read_mesh(fixture("ascii"));  // VTK 9's ASCII, with <InformationKey> in Points
  REQUIRE(ref.num_vertices() == 64);
  REQUIRE(ref.num_tets() == 135);
  REQUIRE(ref.point_data.size() == 3);
  REQUIRE(ref.cell_data.size() == 1);
  CHECK(ref.find_cell_field("label")->integer);
  CHECK(ref.find_point_field("vertex_label")->integer);
  CHECK(!ref.find_point_field("ratio32")->integer);
  CHECK(ref.find_point_field("original_position")->values(5, 1) == 0.5 * 70 + 1e-9 * 5);  // all 17 digits
  for (const char* e : kEncodings) {
    INFO(e);
    const TetMesh m = read_mesh(fixture(e));
    CHECK(m.vertices == ref.vertices);
    CHECK(m.tets == ref.tets);
    REQUIRE(m.point_data.size() == ref.point_data.size());
    REQUIRE(m.cell_data.size() == ref.cell_data.size());
    for (const Field& f : ref.point_data) {
      const Field* g = m.find_point_field(f.name);
      REQUIRE(g);
      CHECK(g->values == f.values);
      CHECK(g->integer == f.integer);
    }
    CHECK(m.find_cell_field("label")->values == ref.find_cell_field("label")->values);
  }
}

TEST_CASE("io: corrupt binary .vtu files are InputErrors naming the file, never crashes") {
  const std::string target = std::string(VPM_TEST_TMP) + "/corrupt_binary.vtu";
  std::uint32_t rng = 2024;
  auto next = [&rng]() { return rng = rng * 1664525u + 1013904223u; };
  int errors = 0;
  for (const char* e : kEncodings) {
    const std::string good = slurp(fixture(e));
    for (int trial = 0; trial < 40; ++trial) {
      std::string text = good;
      if (trial % 2 == 0) {
        text.resize(next() % text.size());
      } else {  // flips anywhere, the binary data and their headers included
        for (int k = 0; k < 4; ++k) text[next() % text.size()] = static_cast<char>(next() & 0xff);
      }
      spit(target, text);
      try {
        read_mesh(target);
      } catch (const InputError& err) {
        ++errors;
        INFO(e << " trial " << trial);
        CHECK_THAT(std::string(err.what()), Catch::StartsWith(target));
      }
    }
  }
  CHECK(errors > 150);
  // what the messages say for the common cases
  std::string cut = slurp(fixture("appended_raw"));
  spit(target, cut.substr(0, cut.size() - 400) + "\n  </AppendedData>\n</VTKFile>\n");
  CHECK_THROWS_WITH(read_mesh(target), Catch::Contains("runs past the data"));
  std::string other = slurp(fixture("binary_zlib"));
  other.replace(other.find("vtkZLibDataCompressor"), 21, "vtkLZ4DataCompressor");
  spit(target, other);
  CHECK_THROWS_WITH(read_mesh(target), Catch::Contains("vtkLZ4DataCompressor") && Catch::Contains("not supported"));
  std::string big = slurp(fixture("binary"));
  big.replace(big.find("LittleEndian"), 12, "BigEndian");
  spit(target, big);
  CHECK_THROWS_WITH(read_mesh(target), Catch::Contains("big-endian"));
}

TEST_CASE("io: vpm writes .vtu as appended raw binary by default and ASCII on request, both read back exactly") {
  TetMesh ref = read_mesh(fixture("ascii"));  // three point fields (one integer, one 3-component), a cell label
  FieldValues wide(ref.num_tets(), 2);
  for (int t = 0; t < ref.num_tets(); ++t) wide.row(t) << std::sin(0.7 * t) * 1e-300, -t * 1e12 / 7.0;
  ref.set_cell_field("wide", wide);
  const std::string tmp = std::string(VPM_TEST_TMP) + "/written_";
  write_mesh(tmp + "binary.vtu", ref);
  write_mesh(tmp + "ascii.vtu", ref, VtuEncoding::ascii);
  const std::string bin = slurp(tmp + "binary.vtu"), txt = slurp(tmp + "ascii.vtu");
  CHECK_THAT(bin, Catch::Contains("<AppendedData encoding=\"raw\">"));
  CHECK(bin.find("format=\"ascii\"") == std::string::npos);
  CHECK_THAT(txt, Catch::Contains("format=\"ascii\""));
  CHECK(txt.find("AppendedData") == std::string::npos);
  for (const std::string& which : {"binary", "ascii"}) {
    INFO(which);
    const TetMesh m = read_mesh(tmp + which + ".vtu");
    CHECK(m.vertices == ref.vertices);
    CHECK(m.tets == ref.tets);
    REQUIRE(m.point_data.size() == ref.point_data.size());
    REQUIRE(m.cell_data.size() == ref.cell_data.size());
    for (const Field& f : ref.point_data) {
      REQUIRE(m.find_point_field(f.name));
      CHECK(m.find_point_field(f.name)->values == f.values);
      CHECK(m.find_point_field(f.name)->integer == f.integer);
    }
    for (const Field& f : ref.cell_data) {
      REQUIRE(m.find_cell_field(f.name));
      CHECK(m.find_cell_field(f.name)->values == f.values);
      CHECK(m.find_cell_field(f.name)->integer == f.integer);
    }
  }
  // ASCII -> binary -> ASCII gives the same bytes
  write_mesh(tmp + "again.vtu", read_mesh(tmp + "binary.vtu"), VtuEncoding::ascii);
  CHECK(slurp(tmp + "again.vtu") == txt);
  // a truncated binary file is an InputError naming it
  spit(tmp + "cut.vtu", bin.substr(0, bin.size() / 2));
  CHECK_THROWS_WITH(read_mesh(tmp + "cut.vtu"), Catch::StartsWith(tmp + "cut.vtu"));
}

TEST_CASE("io: .vtp (VTK PolyData of triangles) reads back what write_surface wrote, other cells refused") {
  const std::string dir = (fs::temp_directory_path() / "vpm_test_vtp").string();
  fs::create_directories(dir);
  TriSurface s;
  s.vertices.resize(4, 3);
  s.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0.1, 0.2, 1.0 / 3;
  s.triangles.resize(4, 3);
  s.triangles << 0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2;
  Eigen::VectorXd sulc(4);
  sulc << -1.5, 0.25, 1.0 / 7, 3;
  s.point_data.push_back({"sulc", sulc, false});
  s.point_data.push_back({"original_position", s.vertices * 2, false});
  s.cell_data.push_back({"label", Eigen::Vector4d(1, 2, 2, 7), true});
  write_surface(dir + "/t.vtp", s);
  const TriSurface r = read_surface(dir + "/t.vtp");
  CHECK(r.vertices == s.vertices);
  CHECK(r.triangles == s.triangles);
  REQUIRE(r.point_data.size() == 2);
  CHECK(r.point_data[0].name == "sulc");
  CHECK(r.point_data[0].values.col(0) == sulc);
  CHECK(r.point_data[1].values == s.vertices * 2);
  REQUIRE(r.cell_data.size() == 1);
  CHECK(r.cell_data[0].integer);
  CHECK(r.cell_data[0].values.col(0) == Eigen::Vector4d(1, 2, 2, 7));
  // a quad among the polys, lines, a mesh file's type: exit-2 errors naming the place
  const std::string text = slurp(dir + "/t.vtp");
  std::string quad = text;
  quad.replace(quad.find("3 6 9 12\n"), 8, "4 6 9 12");
  spit(dir + "/quad.vtp", quad);
  CHECK_THROWS_WITH(read_surface(dir + "/quad.vtp"), Catch::Contains("quad.vtp:") && Catch::Contains("does not close a triangle"));
  std::string lines = text;
  lines.replace(lines.find("NumberOfLines=\"0\""), 17, "NumberOfLines=\"2\"");
  spit(dir + "/lines.vtp", lines);
  CHECK_THROWS_WITH(read_surface(dir + "/lines.vtp"), Catch::Contains("NumberOfLines is not 0"));
  std::string grid = text;
  grid.replace(grid.find("type=\"PolyData\""), 15, "type=\"UnstructuredGrid\"");
  spit(dir + "/grid.vtp", grid);
  CHECK_THROWS_WITH(read_surface(dir + "/grid.vtp"), Catch::Contains("not a VTK PolyData file"));
  fs::remove_all(dir);
}
