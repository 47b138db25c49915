// vpm_bench_volume_map [--runs N] [--out DIR] [MESH...]: the volume-preserving map methods
// (moser = Moser rounds + polish, the default of `vpm map`; moser-recipe = Moser rounds only,
// docs/design.md 4.1; moser-fixed = frozen boundary; paper = the paper's re-solving loop; vsem =
// reweighted harmonic fixed point) on the same meshes, from the same initial map.
//
// Meshes: the given files, else Colin27 at the paper's size (mesh_image of ch2bet.nii.gz,
// 5,200 target vertices, when mricron-data is installed) and an ellipsoid 1.8 : 1 : 0.6
// (icosphere surface -> mesh_surface, about 5,000 vertices). Prints a table, writes
// DIR/volume_map.json (medians of N runs, default 3) and DIR/histogram.svg (vertex and tet
// volume ratio histograms of the initial and final maps of the first mesh, paper Fig. 3).
#include <algorithm>
#include <optional>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "vpm/device.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/metrics.hpp"
#include "vpm/validate.hpp"
#include "vpm/volume_map.hpp"
#include "vpm/volume_map_peers.hpp"
#include "vpm/timing.hpp"

namespace {

using vpm::Clock;
using vpm::seconds_since;


double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The icosphere of `level` subdivisions scaled to semi-axes a, b, c.
vpm::TriSurface ellipsoid_surface(int level, double a, double b, double c) {
  vpm::TriSurface s = vpm::icosphere(level);
  s.vertices = s.vertices * Eigen::Vector3d(a, b, c).asDiagonal();
  return s;
}

struct Variant {
  std::string name;
  vpm::VolumeMapOptions options;
  std::optional<vpm::VolumeMapPeer> peer;  // a peer's rounds (vpm/volume_map_peers.hpp)
};

std::vector<Variant> variants() {
  std::vector<Variant> v;
  vpm::VolumeMapOptions o;
  v.push_back({"moser", o});
  o.polish_rounds = 0;
  v.push_back({"moser-recipe", o});
  o = {};
  o.boundary = vpm::MapBoundary::fixed;
  o.polish_rounds = 0;
  v.push_back({"moser-fixed", o});
  o = {};
  v.push_back({"paper", o, vpm::VolumeMapPeer::paper});
  v.push_back({"vsem", o, vpm::VolumeMapPeer::vsem});
  return v;
}

// Histogram SVG: counts of r in [0, 2] (50 bins), initial (grey) and final (blue), one
// panel for vertex ratios and one for tet ratios.
std::string histogram_svg(const std::string& title, const Eigen::VectorXd& vi, const Eigen::VectorXd& vf,
                          const Eigen::VectorXd& ti, const Eigen::VectorXd& tf, double dvi, double dvf,
                          double dti, double dtf) {
  const int bins = 50, W = 900, H = 380, pw = 400, ph = 260, top = 60;
  auto hist = [&](const Eigen::VectorXd& r) {
    std::vector<double> h(bins, 0);
    for (Eigen::Index i = 0; i < r.size(); ++i) {
      int b = static_cast<int>(std::floor(r(i) / 2.0 * bins));
      h[std::clamp(b, 0, bins - 1)] += 1.0 / static_cast<double>(r.size());
    }
    return h;
  };
  std::ostringstream s;
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H
    << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n"
    << "<text x='" << W / 2 << "' y='22' text-anchor='middle' font-size='15'>" << title << "</text>\n";
  auto panel = [&](int x0, const char* name, const Eigen::VectorXd& a, const Eigen::VectorXd& b, double da,
                   double db) {
    const auto ha = hist(a), hb = hist(b);
    double mx = 0;
    for (int i = 0; i < bins; ++i) mx = std::max({mx, ha[i], hb[i]});
    const double bw = double(pw) / bins;
    const int y0 = top + ph;
    s << "<text x='" << x0 + pw / 2 << "' y='" << top - 12 << "' text-anchor='middle'>" << name << "</text>\n";
    for (int pass = 0; pass < 2; ++pass) {
      const auto& h = pass ? hb : ha;
      const char* col = pass ? "rgba(31,119,180,0.75)" : "rgba(150,150,150,0.6)";
      for (int i = 0; i < bins; ++i) {
        const double hh = mx > 0 ? h[i] / mx * ph : 0;
        s << "<rect x='" << x0 + i * bw << "' y='" << y0 - hh << "' width='" << bw * 0.95 << "' height='" << hh
          << "' fill='" << col << "'/>\n";
      }
    }
    s << "<line x1='" << x0 << "' y1='" << y0 << "' x2='" << x0 + pw << "' y2='" << y0 << "' stroke='black'/>\n";
    for (int k = 0; k <= 4; ++k) {
      const double x = x0 + k * pw / 4.0;
      s << "<line x1='" << x << "' y1='" << y0 << "' x2='" << x << "' y2='" << y0 + 5 << "' stroke='black'/>\n"
        << "<text x='" << x << "' y='" << y0 + 18 << "' text-anchor='middle'>" << 0.5 * k << "</text>\n";
    }
    s << "<text x='" << x0 + pw / 2 << "' y='" << y0 + 34 << "' text-anchor='middle'>volume ratio r (normalised)</text>\n";
    char buf[160];
    std::snprintf(buf, sizeof buf, "initial map: mean |r-1| = %.1f %%", 100 * da);
    s << "<rect x='" << x0 + 8 << "' y='" << top + 4 << "' width='10' height='10' fill='rgba(150,150,150,0.6)'/>"
      << "<text x='" << x0 + 22 << "' y='" << top + 13 << "'>" << buf << "</text>\n";
    std::snprintf(buf, sizeof buf, "volume-preserving map: %.1f %%", 100 * db);
    s << "<rect x='" << x0 + 8 << "' y='" << top + 20 << "' width='10' height='10' fill='rgba(31,119,180,0.75)'/>"
      << "<text x='" << x0 + 22 << "' y='" << top + 29 << "'>" << buf << "</text>\n";
  };
  panel(40, "vertex (dual) volume ratio", vi, vf, dvi, dvf);
  panel(480, "tet volume ratio", ti, tf, dti, dtf);
  s << "</svg>\n";
  return s.str();
}

using NamedMesh = std::pair<std::string, vpm::TetMesh>;

// The given mesh files, else Colin27 at the paper's size (when mricron-data is installed) and
// the ellipsoid.
std::vector<NamedMesh> load_meshes(const std::vector<std::string>& paths) {
  std::vector<NamedMesh> meshes;
  for (const auto& p : paths) {
    vpm::TetMesh m = vpm::read_mesh(p);
    vpm::validate_mesh(m, p);
    meshes.emplace_back(std::filesystem::path(p).filename().string(), std::move(m));
  }
  if (!paths.empty()) return meshes;
  const std::string colin = "/usr/share/mricron/templates/ch2bet.nii.gz";
  vpm::MeshImageOptions mo;
  mo.target_vertices = 5200;
  if (std::filesystem::exists(colin)) {
    try {
      meshes.emplace_back("colin27", vpm::mesh_image_file(colin, mo));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "colin27 skipped: %s\n", e.what());
    }
  }
  try {
    mo.target_vertices = 5000;
    meshes.emplace_back("ellipsoid", vpm::mesh_surface(ellipsoid_surface(4, 1.8, 1.0, 0.6), mo));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ellipsoid skipped: %s\n", e.what());
  }
  return meshes;
}

// `runs` maps of one variant from the same initial map: the last result, its map, the medians.
struct VariantRuns {
  vpm::VolumeMapResult last;
  vpm::Points ball;
  std::string error;
  std::vector<double> total, solve, field, advect, untangle;
};

VariantRuns run_variant(vpm::Device& dev, const vpm::InitialMapResult& im, const Variant& var, int runs) {
  VariantRuns v;
  for (int r = 0; r < runs; ++r) {
    v.ball = im.ball;
    try {
      v.last = var.peer ? vpm::volume_map_peer(dev, im.mesh.vertices, im.mesh.tets, v.ball, var.options, {*var.peer})
                        : vpm::volume_preserving_map(dev, im.mesh.vertices, im.mesh.tets, v.ball, var.options);
    } catch (const std::exception& e) {
      v.error = e.what();
      return v;
    }
    v.total.push_back(v.last.timings.total);
    v.solve.push_back(v.last.timings.solve);
    v.field.push_back(v.last.timings.field);
    v.advect.push_back(v.last.timings.advect);
    v.untangle.push_back(v.last.timings.untangle);
  }
  return v;
}

vpm::Json variant_json(const Variant& var, const VariantRuns& v, const vpm::MapMetrics& m1) {
  vpm::Json j = vpm::Json::object();
  j["method"] = var.name;
  int folds_seen = 0;
  for (const auto& r : v.last.rounds) folds_seen += r.folds_before_untangle;
  j["final"] = vpm::to_json(m1);
  j["rounds"] = static_cast<int>(v.last.rounds.size());
  j["folds_during_rounds"] = folds_seen;
  j["stop_reason"] = v.last.stop_reason;
  vpm::Json t = vpm::Json::object();
  t["total"] = median(v.total);
  t["solve"] = median(v.solve);
  t["field"] = median(v.field);
  t["advect"] = median(v.advect);
  t["untangle"] = median(v.untangle);
  j["timings_s_median"] = t;
  j["report"] = vpm::to_json(v.last);
  return j;
}

// Every variant on one mesh; prints a row each; writes the histogram of the first moser map.
vpm::Json bench_mesh(vpm::Device& dev, const NamedMesh& named, int runs, const std::string& out_dir, bool& svg_done) {
  const auto& [name, mesh] = named;
  auto t0 = Clock::now();
  const vpm::InitialMapResult im = vpm::initial_map(dev, mesh);
  const double t_init = seconds_since(t0);
  const vpm::MapMetrics m0 = vpm::map_metrics(dev, im.mesh.vertices, im.ball, im.mesh.tets);
  vpm::Json jmesh = vpm::Json::object();
  jmesh["name"] = name;
  jmesh["vertices"] = mesh.num_vertices();
  jmesh["tets"] = mesh.num_tets();
  jmesh["refined_vertices"] = im.mesh.num_vertices();
  jmesh["refined_tets"] = im.mesh.num_tets();
  jmesh["initial_map_s"] = t_init;
  jmesh["initial"] = vpm::to_json(m0);
  vpm::Json jv = vpm::Json::array();
  for (const auto& var : variants()) {
    const VariantRuns v = run_variant(dev, im, var, runs);
    if (!v.error.empty()) {
      vpm::Json j = vpm::Json::object();
      j["method"] = var.name;
      j["error"] = v.error;
      std::printf("%-12s %-13s failed: %s\n", name.c_str(), var.name.c_str(), v.error.c_str());
      jv.push_back(j);
      continue;
    }
    const vpm::MapMetrics m1 = vpm::map_metrics(dev, im.mesh.vertices, v.ball, im.mesh.tets);
    jv.push_back(variant_json(var, v, m1));
    std::printf("%-12s %-13s %8.4f %8.4f %8.4f %8.4f %5d %6zu %7.3f %7.3f %7.3f %7.3f %7.3f\n", name.c_str(),
                var.name.c_str(), m0.vertex_volume_ratio.mean_abs_dev, m0.tet_volume_ratio.mean_abs_dev,
                m1.vertex_volume_ratio.mean_abs_dev, m1.tet_volume_ratio.mean_abs_dev, m1.inverted_tets,
                v.last.rounds.size(), median(v.solve), median(v.field), median(v.advect), median(v.untangle),
                median(v.total));
    std::fflush(stdout);
    if (!svg_done && var.name == "moser") {
      svg_done = true;
      const std::string svg = histogram_svg(
          name + ": " + std::to_string(im.mesh.num_vertices()) + " vertices, " + std::to_string(im.mesh.num_tets()) +
              " tets (vpm map, moser)",
          m0.vertex_ratio, m1.vertex_ratio, m0.tet_ratio, m1.tet_ratio, m0.vertex_volume_ratio.mean_abs_dev,
          m1.vertex_volume_ratio.mean_abs_dev, m0.tet_volume_ratio.mean_abs_dev, m1.tet_volume_ratio.mean_abs_dev);
      std::ofstream(out_dir + "/histogram.svg") << svg;
    }
  }
  jmesh["methods"] = jv;
  return jmesh;
}

}  // namespace

int run(int argc, char** argv) {
  int runs = 3;
  std::string out_dir = VPM_BENCH_OUT;
  std::vector<std::string> paths;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--runs") && i + 1 < argc) runs = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--out") && i + 1 < argc) out_dir = argv[++i];
    else if (argv[i][0] == '-') throw vpm::InputError(std::string("unknown option ") + argv[i]);
    else paths.push_back(argv[i]);
  }
  std::filesystem::create_directories(out_dir);
  vpm::Device& dev = vpm::Device::current();
  const std::vector<NamedMesh> meshes = load_meshes(paths);

  vpm::Json results = vpm::Json::object();
  results["device"] = dev.name();
  results["runs"] = runs;
  vpm::Json jm = vpm::Json::array();
  std::printf("device: %s, %d runs (medians)\n", dev.name().c_str(), runs);
  std::printf("%-12s %-13s %8s %8s %8s %8s %5s %6s %7s %7s %7s %7s %7s\n", "mesh", "method", "v.init",
              "t.init", "v.final", "t.final", "folds", "rounds", "solve", "field", "advect", "untangl", "total");
  bool svg_done = false;
  for (const auto& named : meshes) jm.push_back(bench_mesh(dev, named, runs, out_dir, svg_done));
  results["meshes"] = jm;
  vpm::write_json_file(out_dir + "/volume_map.json", results);
  std::printf("wrote %s/volume_map.json and %s/histogram.svg\n", out_dir.c_str(), out_dir.c_str());
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const vpm::InputError& e) {
    std::fprintf(stderr, "vpm_bench_volume_map: %s\nusage: vpm_bench_volume_map [--runs R] [--out DIR] [MESH ...]\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vpm_bench_volume_map: %s\n", e.what());
    return 3;
  }
}
