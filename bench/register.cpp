// Registration benchmark: 20 random landmarks moved by up to 0.2 ball radii on ball
// meshes of about the paper's size (26k tets) and ~1M tets. Prints a table and writes JSON.
//
//   vpm_bench_register [--quick] [--runs R] [--large N] [--out FILE]   (N: cube subdivisions, 6 N^3 tets; 55)
//
// The device is VPM_DEVICE's (PoCL CPU here). Times are medians of R runs.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <random>
#include <string>

#include "support/fixtures.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/json.hpp"
#include "vpm/metrics.hpp"
#include "vpm/registration.hpp"
#include "bench_util.hpp"

using namespace vpm;
using bench::median;

namespace {

// Unit cube split into n^3 cells of 6 Kuhn tets, [-1,1]^3 mapped into the ball by
//   x = p ((1 - m) + m^2 / |p|),  m = max |p_i|,
// which keeps the centre cube-like and sends the cube surface radially onto the sphere; along
// each ray the radius grows monotonically (d|x|/dm >= 2 - sqrt 3), so no tet inverts (checked).
// Tets of the outer layer with four vertices on one cube face become flat on the sphere.
// (n+1)^3 vertices, 6 n^3 tets.
TetMesh ball_mesh(int n) {
  TetMesh m = vpm::test::cube_mesh(n);  // [0,1]^3, positively oriented Kuhn tets
  for (Eigen::Index v = 0; v < m.vertices.rows(); ++v) {
    Eigen::RowVector3d p = 2.0 * m.vertices.row(v).array() - 1.0;
    const double inf = p.cwiseAbs().maxCoeff(), r = p.norm();
    if (r > 0) p *= (1 - inf) + inf * inf / r;
    m.vertices.row(v) = p;
  }
  const Eigen::VectorXd vol = tet_volumes(m.vertices, m.tets);
  if (vol.minCoeff() <= 0) throw std::runtime_error("ball_mesh: the cube-to-ball map inverted a tet");
  return m;
}

// 20 landmarks in the ball of radius 0.8, each moved by a random vector of length <= move
// (drawn so that a move of 0.2 stays inside radius 0.9; fixed seed).
void landmarks(int n, unsigned seed, double move, Points& p, Points& q) {
  test::random_landmarks(n, seed, 0.8, 0.2, 0.9, move, p, q);
}

struct Case {
  std::string name;
  int n;          // ball_mesh(n): 6 n^3 tets
  int runs;
  RegistrationOptions opt;
  bool host = false;
  double move = 0.2;  // largest landmark displacement
};

Json run_case(const Case& c, const TetMesh& m) {
  Points p, q;
  landmarks(20, 2014, c.move, p, q);
  auto dev = c.host ? Device::host() : std::shared_ptr<Device>(&Device::current(), [](Device*) {});
  Json j = Json::object();
  j["case"] = c.name;
  j["device"] = dev->name();
  j["vertices"] = m.num_vertices();
  j["tets"] = m.num_tets();
  j["landmarks"] = static_cast<long>(p.rows());
  j["steps"] = c.opt.steps;
  j["boundary"] = to_string(c.opt.boundary);
  j["field"] = to_string(c.opt.field);
  j["width_factor"] = c.opt.width_factor;
  j["max_landmark_move"] = c.move;
  std::vector<double> total, advect, fit;
  RegistrationResult res;
  Points x;
  for (int r = 0; r < c.runs; ++r) {
    x = m.vertices;
    try {
      res = register_landmarks(*dev, x, m.tets, p, q, c.opt);
    } catch (const NumericalError& e) {
      j["error"] = e.what();
      std::printf("%-22s %8d  FAILED: %s\n", c.name.c_str(), m.num_tets(), e.what());
      return j;
    }
    total.push_back(res.report.timings.total);
    advect.push_back(res.report.timings.advect);
    fit.push_back(res.report.timings.fit);
  }
  const MapMetrics mm = map_metrics(*dev, m.vertices, x, m.tets);
  // how many inverted tets are flat outer-layer tets with all four vertices on the sphere
  int inverted_flat = 0;
  {
    const Eigen::VectorXd v1 = tet_volumes(x, m.tets);
    for (Eigen::Index t = 0; t < v1.size(); ++t) {
      if (v1(t) > 0) continue;
      bool all = true;
      for (int c = 0; c < 4; ++c) all = all && std::fabs(m.vertices.row(m.tets(t, c)).norm() - 1) < 1e-12;
      inverted_flat += all;
    }
  }
  const double centres = static_cast<double>(res.report.fit.samples_per_field + res.report.fit.boundary_constraints);
  const double evals = static_cast<double>(x.rows() + p.rows()) * centres * 4.0 * c.opt.steps;
  j["runs"] = c.runs;
  j["time_s_median"] = median(total);
  j["advect_s_median"] = median(advect);
  j["fit_s_median"] = median(fit);
  Json all = Json::array();
  for (double t : total) all.push_back(t);
  j["time_s_all"] = all;
  j["kernel_evaluations"] = evals;
  j["kernel_evaluations_per_s"] = evals / median(advect);
  j["landmark_rms_error"] = res.landmark_rms_error;
  j["landmark_max_error"] = res.landmark_max_error;
  j["max_normal_velocity"] = res.max_normal_velocity;
  j["width"] = res.report.width;
  j["folded_by_flow"] = res.report.folded_by_flow;
  if (res.report.untangle) j["untangle"] = to_json(*res.report.untangle);
  j["inverted_tets"] = mm.inverted_tets;
  j["inverted_tets_all_vertices_on_sphere"] = inverted_flat;
  j["vertex_volume_ratio"] = to_json(mm.vertex_volume_ratio);
  j["tet_volume_ratio"] = to_json(mm.tet_volume_ratio);
  j["boundary_max_radius_error"] = mm.boundary_max_radius_error;
  j["report"] = to_json(res);
  std::printf("%-22s %8d %9.2e %9.2e %8.3f%% %8.3f%% %4d %4d/%-3d %9.1e %8.3f %8.3f %9.2e\n", c.name.c_str(),
              m.num_tets(), res.landmark_rms_error, res.landmark_max_error,
              100 * mm.vertex_volume_ratio.mean_abs_dev, 100 * mm.tet_volume_ratio.mean_abs_dev,
              res.report.folded_by_flow, mm.inverted_tets, inverted_flat, res.max_normal_velocity, median(total), median(advect),
              evals / median(advect));
  std::fflush(stdout);
  return j;
}

// The benchmark's cases: paper size with and without restoration; unless quick, the host run,
// smaller moves, kernel widths, boundary and field variants, and 50k / 200k / ~1M tets.
std::vector<Case> make_cases(bool quick, int runs, int large) {
  std::vector<Case> cases;
  RegistrationOptions def;
  def.refuse_folds = false;  // measure folds instead of stopping
  cases.push_back({"paper-size", 16, runs, def});
  RegistrationOptions no_restore = def;
  no_restore.restore_volumes = false;
  cases.push_back({"no volume restore", 16, runs, no_restore});
  if (!quick) {
    Case h{"paper-size host", 16, 1, def, true};
    cases.push_back(h);
    for (double mv : {0.05, 0.1}) {
      Case c{"move<=" + std::to_string(mv).substr(0, 4), 16, 1, def};
      c.move = mv;
      cases.push_back(c);
    }
    for (double f : {1.0, 2.0}) {
      RegistrationOptions o = def;
      o.width_factor = f;
      cases.push_back({"width x" + std::to_string(f).substr(0, 3), 16, 1, o});
    }
    RegistrationOptions loo = def;
    loo.width_loo = true;
    cases.push_back({"width loo", 16, 1, loo});
    RegistrationOptions samples = def;
    samples.boundary = RegistrationBoundary::Samples;
    cases.push_back({"boundary samples", 16, 1, samples});
    RegistrationOptions none = def;
    none.boundary = RegistrationBoundary::None;
    cases.push_back({"boundary none", 16, 1, none});
    RegistrationOptions steady = def;
    steady.field = RegistrationField::Steady;
    cases.push_back({"steady field (paper)", 16, 1, steady});
    cases.push_back({"50k tets", 20, 1, def});
    cases.push_back({"200k tets", 32, 1, def});
    cases.push_back({"~1M tets", large, std::max(1, runs / 2), def});
  }
  return cases;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  int runs = 3, large = 55;
  std::string out = VPM_BENCH_OUT "/register.json";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") quick = true;
    else if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (a == "--large" && i + 1 < argc) {
      large = std::atoi(argv[++i]);  // cube subdivisions n: 6 n^3 tets
      if (large < 2 || large > 150) {
        std::cerr << "vpm_bench_register: --large " << argv[i] << ": subdivisions n (6 n^3 tets) must be 2..150\n";
        return 2;
      }
    }
    else if (a == "--out" && i + 1 < argc) out = argv[++i];
    else {
      std::cerr << "usage: vpm_bench_register [--quick] [--runs R] [--large N] [--out FILE]\n";
      return 2;
    }
  }
  try {
    const std::vector<Case> cases = make_cases(quick, runs, large);
    std::printf("%-22s %8s %9s %9s %9s %9s %4s %8s %9s %8s %8s %9s\n", "case", "tets", "lm_rms", "lm_max",
                "vert|r-1|", "tet|r-1|", "fold", "inv/flat", "max|u.n|", "total_s", "advect_s", "evals/s");
    Json results = Json::array();
    std::map<int, TetMesh> meshes;
    for (const auto& c : cases) {
      if (!meshes.count(c.n)) meshes[c.n] = ball_mesh(c.n);
      results.push_back(run_case(c, meshes[c.n]));
    }
    Json doc = Json::object();
    doc["benchmark"] = "register";
    doc["device"] = Device::current().name();
    doc["landmarks"] = "20 random in radius 0.8, each moved by a random vector of length <= max_landmark_move (same seed 2014 and directions for every scale)";
    doc["mesh"] = "Kuhn-subdivided cube [-1,1]^3 mapped by x = p((1-m) + m^2/|p|), m = max|p_i| (bench/register.cpp)";
    doc["results"] = results;
    std::filesystem::create_directories(std::filesystem::path(out).parent_path());
    write_json_file(out, doc);
    std::cout << "wrote " << out << '\n';
  } catch (const std::exception& e) {
    std::cerr << "vpm_bench_register: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
