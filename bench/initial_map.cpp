// Initial map benchmark: time per stage and initial distortion on synthetic shapes of about
// the paper's size (26k tets) and on meshes given on the command line (e.g. Colin27).
//
//   vpm_bench_initial_map [--runs R] [--out FILE.json] [--untangle never|if-folded|always]
//                         [--area-correction] [--scale S] [MESH ...]
//
// Prints one table row per shape (median over R runs of each stage) and writes JSON
// (default <build>/bench-results/initial_map.json). The paper's harmonic start had 32.3 % volume
// distortion (vertex mean |r-1|) on its 26k-tet brain.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "support/fixtures.hpp"
#include "support/shapes.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/validate.hpp"
#include "bench_util.hpp"

using namespace vpm;
using bench::median;

namespace {
// The synthetic shapes at `scale`, then the given mesh files (skipped with a message if bad).
std::vector<std::pair<std::string, TetMesh>> load_shapes(double scale, const std::vector<std::string>& paths) {
  std::vector<std::pair<std::string, TetMesh>> shapes;
  const int nb = std::max(2, static_cast<int>(16 * scale));
  const int nc = std::max(2, static_cast<int>(11 * scale));
  shapes.push_back({"ball_mesh(" + std::to_string(nb) + ")", test::ball_mesh(nb)});
  shapes.push_back({"ellipsoid 1.8:1:0.6 (" + std::to_string(nb) + ")", test::ellipsoid_mesh(nb)});
  shapes.push_back({"bent C (" + std::to_string(nc) + ")", test::bent_mesh(nc)});
  shapes.push_back({"dumbbell (" + std::to_string(nc) + ")", test::dumbbell_mesh(nc)});
  for (const auto& p : paths) {
    try {
      TetMesh m = read_mesh(p);
      validate_mesh(m, p);
      shapes.push_back({std::filesystem::path(p).filename().string(), std::move(m)});
    } catch (const std::exception& e) {
      std::fprintf(stderr, "skipping %s: %s\n", p.c_str(), e.what());
    }
  }

  return shapes;
}

// `runs` initial maps of one shape: a table row (printed) and its JSON (medians, last report).
Json bench_shape(Device& dev, const std::string& name, const TetMesh& mesh, const InitialMapOptions& opt, int runs) {
  std::vector<double> ts, tb, th, tu, tt;
  InitialMapReport last;
  std::string error;
  for (int r = 0; r < runs; ++r) {
    try {
      const InitialMapResult res = initial_map(dev, mesh, opt);
      last = res.report;
      ts.push_back(last.timings.split);
      tb.push_back(last.timings.boundary);
      th.push_back(last.timings.harmonic);
      tu.push_back(last.timings.untangle);
      tt.push_back(last.timings.total);
    } catch (const NumericalError& e) {
      error = e.what();
      break;
    }
  }
  Json row = Json::object();
  row["shape"] = name;
  row["vertices"] = mesh.num_vertices();
  row["tets"] = mesh.num_tets();
  if (!error.empty()) {
    row["error"] = error;
    std::printf("%-28s %7d %7d | refused: %s\n", name.c_str(), mesh.num_vertices(), mesh.num_tets(), error.c_str());
    return row;
  }
  Json& t = row["median_s"];
  t["split"] = median(ts);
  t["boundary"] = median(tb);
  t["harmonic"] = median(th);
  t["untangle"] = median(tu);
  t["total"] = median(tt);
  row["report"] = to_json(last);
  std::printf("%-28s %7d %7d | %7.3f %7.3f %7.3f %7.3f %7.3f | %5d %5d | %7.4f %7.4f | %6.3f %6.2f\n",
              name.c_str(), mesh.num_vertices(), mesh.num_tets(), median(ts), median(tb), median(th),
              median(tu), median(tt), last.folds_before_untangle, last.folds_after_untangle,
              last.metrics.vertex_volume_ratio.mean_abs_dev, last.metrics.tet_volume_ratio.mean_abs_dev,
              last.boundary.area_distortion_final, last.min_dihedral_deg);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 3;
  double scale = 1.0;
  std::string out = VPM_BENCH_OUT "/initial_map.json";
  InitialMapOptions opt;
  std::vector<std::string> paths;
  std::string only;  // run only shapes whose name contains this
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--runs") runs = std::max(1, std::atoi(next().c_str()));
    else if (a == "--out") out = next();
    else if (a == "--scale") scale = std::atof(next().c_str());
    else if (a == "--area-correction") opt.area_correction = true;
    else if (a == "--lbfgs") opt.untangle_options.max_lbfgs_iterations = std::atoi(next().c_str());
    else if (a == "--rings") opt.local_untangle_rings = std::atoi(next().c_str());
    else if (a == "--only") only = next();
    else if (a == "--untangle") {
      const std::string u = next();
      opt.untangle = u == "never" ? InitialMapOptions::Untangle::Never
                     : u == "always" ? InitialMapOptions::Untangle::Always
                                     : InitialMapOptions::Untangle::IfFolded;
    } else if (a.rfind("--", 0) == 0) {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    } else paths.push_back(a);
  }
  Device& dev = Device::current();
  const auto shapes = load_shapes(scale, paths);

  Json root = Json::object();
  root["benchmark"] = "initial_map";
  root["device"] = dev.name();
  root["hardware_threads"] = static_cast<int>(std::thread::hardware_concurrency());
  root["runs"] = runs;
  root["paper_harmonic_vertex_mean_abs_dev"] = 0.323;
  Json rows = Json::array();
  std::printf("device %s, %d runs (median), paper harmonic start: 32.3 %%\n", dev.name().c_str(), runs);
  std::printf("%-28s %7s %7s | %7s %7s %7s %7s %7s | %5s %5s | %7s %7s | %6s %6s\n", "shape", "verts", "tets",
              "split", "bound", "harm", "untgl", "total", "foldH", "foldU", "v|r-1|", "t|r-1|", "areaD",
              "mindih");
  for (const auto& [name, mesh] : shapes) {
    if (!only.empty() && name.find(only) == std::string::npos) continue;
    rows.push_back(bench_shape(dev, name, mesh, opt, runs));
  }
  root["results"] = rows;
  std::filesystem::create_directories(std::filesystem::path(out).parent_path().empty()
                                          ? std::filesystem::path(".")
                                          : std::filesystem::path(out).parent_path());
  write_json_file(out, root);
  std::printf("wrote %s\n", out.c_str());
  return 0;
}
