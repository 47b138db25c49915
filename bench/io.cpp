// vpm_bench_io [N] [DIR]: writes and reads a cube mesh of 6 N^3 tets (N = 55: ~1M tets) in
// every mesh format, prints the times and file sizes, writes DIR/bench_io.json.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "support/fixtures.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/timing.hpp"

namespace {
vpm::TetMesh cube(int n) {
  vpm::TetMesh m = vpm::test::cube_mesh(n);
  vpm::FieldValues label(m.num_tets(), 1), ratio(m.num_vertices(), 1);
  for (int i = 0; i < m.num_tets(); ++i) label(i, 0) = 1 + i % 3;
  for (int i = 0; i < m.num_vertices(); ++i) ratio(i, 0) = 1.0 + 1.0 / (7.0 + i);
  m.set_cell_field("label", label, true);
  m.set_point_field("vertex_volume_ratio", ratio);
  return m;
}
}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 55;
  if (n < 2 || argc > 3) {
    std::fprintf(stderr, "usage: vpm_bench_io [N (cubes a side, >= 2; default 55)] [DIR]\n");
    return 2;
  }
  const std::string dir = argc > 2 ? argv[2] : std::filesystem::temp_directory_path().string();
  const vpm::TetMesh m = cube(n);
  std::printf("cube mesh: %d vertices, %d tets\n%-6s %10s %10s %10s\n", m.num_vertices(),
              m.num_tets(), "format", "write_s", "read_s", "MB");
  vpm::Json j = vpm::Json::object();
  j["vertices"] = m.num_vertices();
  j["tets"] = m.num_tets();
  for (const char* ext : {".node", ".mesh", ".vtu", ".msh"}) {
    const std::string path = dir + "/bench_io" + ext;
    vpm::Stopwatch sw;
    vpm::write_mesh(path, m);
    const double w = sw.seconds();
    sw.restart();
    const vpm::TetMesh r = vpm::read_mesh(path);
    const double rd = sw.seconds();
    double mb = std::filesystem::file_size(path) / 1e6;
    if (std::string(ext) == ".node") mb += std::filesystem::file_size(dir + "/bench_io.ele") / 1e6;
    const bool same = r.vertices == m.vertices && r.tets == m.tets;
    std::printf("%-6s %10.3f %10.3f %10.1f %s\n", ext, w, rd, mb, same ? "" : "MISMATCH");
    vpm::Json& e = j["formats"][ext + 1];
    e["write_s"] = w;
    e["read_s"] = rd;
    e["megabytes"] = mb;
    e["exact"] = same;
    std::filesystem::remove(path);
  }
  for (const char* extra : {"/bench_io.ele", "/bench_io.face"}) std::filesystem::remove(dir + extra);
  vpm::write_json_file(dir + "/bench_io.json", j);
  return 0;
}
