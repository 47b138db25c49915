// vpm_bench_harmonic [--sizes 100000,400000,1600000] [--repeats 3] [--json FILE] [MESH ...]:
// the initial map's harmonic step (K x = 0 inside, x given on the boundary, three columns) by
// PoissonSolver::solve_dirichlet on the selected device (VPM_DEVICE): the three columns as one
// block of Jacobi CG (the default, one pass over the matrix per iteration for all) against the
// same solver asked one column at a time. Boundary values: each boundary vertex's direction
// from the centroid (a radial projection onto the sphere, standing in for the sphere map); the
// interior starts at 0. Meshes: jittered voxel ellipsoids of about the given tet counts, then the
// given files. Prints a table (medians of the repeats) and writes JSON; both answers must agree
// bit for bit.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "support/shapes.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/solver.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"
#include "bench_util.hpp"

using namespace vpm;
using bench::median;

namespace {

struct Result {
  std::string name;
  int vertices = 0, tets = 0, iterations = 0;
  long nnz = 0;
  double block_s = 0, columns_s = 0, max_difference = 0;
};

Result run(Device& dev, const std::string& name, const TetMesh& m, int repeats) {
  Result r;
  r.name = name;
  r.vertices = m.num_vertices();
  r.tets = m.num_tets();
  const std::vector<char> boundary = boundary_vertex_mask(r.vertices, boundary_faces(m.tets));
  const Eigen::RowVector3d c = m.vertices.colwise().mean();
  FieldValues values = FieldValues::Zero(r.vertices, 3);
  for (int i = 0; i < r.vertices; ++i)
    if (boundary[static_cast<size_t>(i)]) values.row(i) = (m.vertices.row(i) - c).normalized();
  PoissonSolver solver(dev, r.vertices, m.tets);
  solver.set_positions(m.vertices);
  r.nnz = solver.laplacian().nnz();
  std::vector<double> block_t, columns_t;
  FieldValues block, columns(r.vertices, 3);
  for (int k = 0; k < repeats; ++k) {
    auto t0 = Clock::now();
    block.resize(0, 0);  // start from 0 inside
    r.iterations = solver.solve_dirichlet(boundary, values, block).iterations;
    block_t.push_back(seconds_since(t0));
    t0 = Clock::now();
    for (int col = 0; col < 3; ++col) {
      FieldValues v = values.col(col), x;
      solver.solve_dirichlet(boundary, v, x);
      columns.col(col) = x.col(0);
    }
    columns_t.push_back(seconds_since(t0));
  }
  r.block_s = median(block_t);
  r.columns_s = median(columns_t);
  r.max_difference = (block - columns).cwiseAbs().maxCoeff();
  return r;
}

}  // namespace

int main(int argc, char** argv) try {
  const bench::SizedRun run_opts = bench::parse_sized_run(argc, argv, {{100000, 400000, 1600000}, 3, "harmonic.json", {}},
                                                          "usage: vpm_bench_harmonic [--sizes N,N,...] [--repeats R] [--json FILE] [MESH ...]");
  const std::vector<long>& sizes = run_opts.sizes;
  const std::vector<std::string>& files = run_opts.files;
  const int repeats = run_opts.repeats;
  const std::string& json_path = run_opts.json;
  Device& dev = Device::current();
  std::printf("device: %s, %d repeats (medians)\n", dev.name().c_str(), repeats);
  std::printf("%-16s %9s %9s %10s %6s %9s %9s %7s %9s\n", "mesh", "vertices", "tets", "nnz", "iters", "block s",
              "columns s", "ratio", "max diff");
  Json out = Json::object();
  out["device"] = dev.name();
  out["repeats"] = repeats;
  Json& rows = out["meshes"] = Json::array();
  bool identical = true;
  auto report = [&](const Result& r) {
    std::printf("%-16s %9d %9d %10ld %6d %9.3f %9.3f %7.2f %9.2g\n", r.name.c_str(), r.vertices, r.tets, r.nnz,
                r.iterations, r.block_s, r.columns_s, r.columns_s / r.block_s, r.max_difference);
    Json j = Json::object();
    j["name"] = r.name;
    j["vertices"] = r.vertices;
    j["tets"] = r.tets;
    j["nnz"] = static_cast<double>(r.nnz);
    j["iterations"] = r.iterations;
    j["block_s_median"] = r.block_s;
    j["columns_s_median"] = r.columns_s;
    j["speedup"] = r.columns_s / r.block_s;
    j["max_difference"] = r.max_difference;
    rows.push_back(j);
    identical = identical && r.max_difference == 0;
  };
  for (long n : sizes) report(run(dev, "ellipsoid-" + std::to_string(n / 1000) + "k", test::voxel_ellipsoid_mesh(n), repeats));
  for (const std::string& f : files) report(run(dev, f.substr(f.find_last_of('/') + 1), read_mesh(f), repeats));
  write_json_file(json_path, out);
  std::printf("wrote %s\n", json_path.c_str());
  if (!identical) {
    std::fprintf(stderr, "vpm_bench_harmonic: the block and the column solves differ\n");
    return 3;
  }
  return 0;
} catch (const InputError& e) {
  std::fprintf(stderr, "vpm_bench_harmonic: %s\n", e.what());
  return 2;
} catch (const std::exception& e) {
  std::fprintf(stderr, "vpm_bench_harmonic: %s\n", e.what());
  return 3;
}
