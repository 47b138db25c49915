// Table 1 of Hu, Zou & Hua 2014 reproduced on this machine: Colin27 (Debian's mricron-data)
// meshed once, its vertices moved by seeded smooth incompressible deformations (the time-1 flow
// of a divergence-free field, the curl of Gaussian vector potentials, then a rotation of up to
// 10 degrees; same connectivity, so the vertex correspondence is known), the original and each
// deformed mesh mapped to the ball independently (initial harmonic map, and the full
// volume-preserving map), and the corresponding vertices compared in the ball after the best
// rotation (Kabsch). Prints a table and writes JSON (also log-ratio histograms for Fig. 3).
//
//   vpm_bench_paper [--seeds N] [--amplitude F] [--target-vertices V] [--data DIR] [--out FILE]
//
// Defaults: 5 seeds, amplitude 1 (F scales the flow), 5200 vertices (the paper's size),
// <build>/bench-results/paper/table1.json.
// Tables 2 and Fig. 3 come from bench/paper/run.sh (docs/paper.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "support/incompressible.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/device.hpp"
#include "vpm/geometry.hpp"
#include "vpm/image.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/metrics.hpp"
#include "vpm/timing.hpp"
#include "vpm/validate.hpp"
#include "bench_util.hpp"

using namespace vpm;
using bench::median;
using Vec = Eigen::Vector3d;

namespace {

// Brain centroid c and mean radius R: 4 potentials centred within R/2 of c, width s = 0.35 R,
// |a_k| chosen so each term's speed peaks at 3-6 % of R (support/incompressible.hpp).
struct Deformed {
  Points vertices;
  double rotation_deg = 0, max_displacement = 0;  // displacement in units of R
};

Deformed deform(const Points& v, unsigned seed, double max_rotation_deg, double amplitude) {
  const Vec c = v.colwise().mean().transpose();
  double R = 0;
  for (Eigen::Index i = 0; i < v.rows(); ++i) R += (v.row(i).transpose() - c).norm();
  R /= v.rows();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), mag(0.03, 0.06);
  test::IncompressibleFlow f;
  f.width = 0.35 * R;
  for (int k = 0; k < 4; ++k) {
    Vec off(u(rng), u(rng), u(rng)), a(u(rng), u(rng), u(rng));
    f.centres.push_back(c + 0.5 * R * off / std::max(1.0, off.norm()));
    f.potentials.push_back(amplitude * a.normalized() * mag(rng) * R * f.width / std::exp(-0.5));
  }
  std::normal_distribution<double> g;
  Deformed d;
  d.rotation_deg = max_rotation_deg * std::uniform_real_distribution<double>(0, 1)(rng);
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(d.rotation_deg * M_PI / 180, Vec(g(rng), g(rng), g(rng)).normalized()).toRotationMatrix();
  d.vertices.resize(v.rows(), 3);
  for (Eigen::Index i = 0; i < v.rows(); ++i) {
    const Vec x = v.row(i).transpose(), y = f.flow(x);
    d.max_displacement = std::max(d.max_displacement, (y - x).norm() / R);
    d.vertices.row(i) = (c + rot * (y - c)).transpose();
  }
  return d;
}

// Mean |R q_i - p_i| over the first n rows after the rotation R minimising it (Kabsch; both
// sets live in the unit ball about the origin, so no translation).
double kabsch_mean_distance(const Points& p, const Points& q, Eigen::Index n) {
  const Eigen::Matrix3d H = q.topRows(n).transpose() * p.topRows(n);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  const Eigen::Matrix3d R = svd.matrixV() * D * svd.matrixU().transpose();
  double s = 0;
  for (Eigen::Index i = 0; i < n; ++i) s += (R * q.row(i).transpose() - p.row(i).transpose()).norm();
  return s / n;
}

struct Maps {
  BallMap harmonic, volume;
};

Maps map_both(Device& dev, TetMesh mesh, const std::string& name) {
  const ValidationReport vr = validate_mesh(mesh, name);
  BallMapOptions initial_only;
  initial_only.volume.rounds = 0;
  return {map_to_ball(dev, mesh, vr, name, initial_only), map_to_ball(dev, mesh, vr, name)};
}

// Histogram of log r over [-0.6, 0.6] in 120 bins of 0.01 (values beyond go to the end bins).
Json log_histogram(const Eigen::VectorXd& r) {
  constexpr int kBins = 120;
  constexpr double kLo = -0.6, kWidth = 0.01;
  std::vector<long> bins(kBins, 0);
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    if (!(r(i) > 0)) continue;
    const int b = static_cast<int>(std::floor((std::log(r(i)) - kLo) / kWidth));
    bins[static_cast<size_t>(std::clamp(b, 0, kBins - 1))]++;
  }
  Json j = Json::object();
  j["lo"] = kLo;
  j["hi"] = kLo + kBins * kWidth;
  Json counts = Json::array();
  for (long c : bins) counts.push_back(c);
  j["counts"] = counts;
  return j;
}

struct Settings {
  int seeds = 5, target_vertices = 5200;
  double amplitude = 1;  // scales the flow (1: each term peaks at 3-6 % of R)
  std::string data = "/usr/share/mricron/templates", out = VPM_BENCH_OUT "/paper/table1.json";
};

Json stats_json(const MapMetrics& m) {
  Json j = Json::object();
  j["vertex_mean_abs_dev"] = m.vertex_volume_ratio.mean_abs_dev;
  j["tet_mean_abs_dev"] = m.tet_volume_ratio.mean_abs_dev;
  j["inverted_tets"] = m.inverted_tets;
  return j;
}

Settings parse_settings(int argc, char** argv) {
  Settings st;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--seeds" && i + 1 < argc) st.seeds = std::atoi(argv[++i]);
    else if (a == "--target-vertices" && i + 1 < argc) st.target_vertices = std::atoi(argv[++i]);
    else if (a == "--amplitude" && i + 1 < argc) st.amplitude = std::atof(argv[++i]);
    else if (a == "--data" && i + 1 < argc) st.data = argv[++i];
    else if (a == "--out" && i + 1 < argc) st.out = argv[++i];
    else throw std::invalid_argument("usage: vpm_bench_paper [--seeds N] [--amplitude F] [--target-vertices V] [--data DIR] [--out FILE]");
  }
  return st;
}

struct Series {
  std::vector<double> dh, dv, hv, ht, vv, vt, defo;
};

Json summary_json(const Series& s) {
  Json med = Json::object();
  med["harmonic_displacement"] = median(s.dh);
  med["volume_displacement"] = median(s.dv);
  med["harmonic_vertex_mean_abs_dev"] = median(s.hv);
  med["harmonic_tet_mean_abs_dev"] = median(s.ht);
  med["volume_vertex_mean_abs_dev"] = median(s.vv);
  med["volume_tet_mean_abs_dev"] = median(s.vt);
  med["deformation_tet_mean_abs_dev"] = median(s.defo);
  return med;
}

}  // namespace

int main(int argc, char** argv) try {
  const Settings st = parse_settings(argc, argv);
  Device& dev = Device::current();
  MeshImageOptions mo;
  mo.target_vertices = st.target_vertices;
  const TetMesh mesh = mesh_image(read_nifti(st.data + "/ch2bet.nii.gz"), mo);
  const Eigen::Index n = mesh.num_vertices();
  const Maps orig = map_both(dev, mesh, "colin27");
  Json runs = Json::array();
  Series S;
  auto &dh = S.dh, &dv = S.dv, &hv = S.hv, &ht = S.ht, &vv = S.vv, &vt = S.vt, &defo = S.defo;
  std::printf("Table 1 (Colin27, %ld vertices, %ld tets, device %s)\n", static_cast<long>(n),
              static_cast<long>(mesh.num_tets()), dev.name().c_str());
  std::printf("%5s %8s %9s %12s | %-26s | %-26s\n", "seed", "rot deg", "max disp", "deform |r-1|",
              "harmonic: disp vert/tet", "volume-pres.: disp vert/tet");
  for (int seed = 1; seed <= st.seeds; ++seed) {
    const auto t0 = Clock::now();
    const Deformed d = deform(mesh.vertices, static_cast<unsigned>(seed), 10.0, st.amplitude);
    TetMesh moved = mesh;
    moved.vertices = d.vertices;
    const MapMetrics dm = map_metrics(dev, mesh.vertices, moved.vertices, mesh.tets);
    const Maps m = map_both(dev, moved, "deformed");
    const double h = kabsch_mean_distance(orig.harmonic.mesh.vertices, m.harmonic.mesh.vertices, n);
    const double v = kabsch_mean_distance(orig.volume.mesh.vertices, m.volume.mesh.vertices, n);
    dh.push_back(h), dv.push_back(v), defo.push_back(dm.tet_volume_ratio.mean_abs_dev);
    hv.push_back(m.harmonic.initial.vertex_volume_ratio.mean_abs_dev), ht.push_back(m.harmonic.initial.tet_volume_ratio.mean_abs_dev);
    vv.push_back(m.volume.final.vertex_volume_ratio.mean_abs_dev), vt.push_back(m.volume.final.tet_volume_ratio.mean_abs_dev);
    std::printf("%5d %8.1f %8.1f%% %11.3f%% | %6.2f%%  %6.1f%% / %6.1f%% | %6.2f%%  %6.2f%% / %6.2f%%  (%.0f s)\n", seed,
                d.rotation_deg, 100 * d.max_displacement, 100 * dm.tet_volume_ratio.mean_abs_dev, 100 * h, 100 * hv.back(),
                100 * ht.back(), 100 * v, 100 * vv.back(), 100 * vt.back(), seconds_since(t0));
    Json r = Json::object();
    r["seed"] = seed;
    r["rotation_deg"] = d.rotation_deg;
    r["max_displacement_of_radius"] = d.max_displacement;
    r["deformation_tet_mean_abs_dev"] = dm.tet_volume_ratio.mean_abs_dev;
    r["harmonic_displacement"] = h;
    r["volume_displacement"] = v;
    r["harmonic"] = stats_json(m.harmonic.initial);
    r["volume"] = stats_json(m.volume.final);
    runs.push_back(r);
  }
  std::printf("median over %d seeds: harmonic %.2f %% displacement, %.1f %% / %.1f %% distortion; volume-preserving "
              "%.2f %%, %.2f %% / %.2f %%   (paper: 3.09 %% / 32.3 %%, 2.32 %% / 12.9 %%)\n",
              st.seeds, 100 * median(dh), 100 * median(hv), 100 * median(ht), 100 * median(dv), 100 * median(vv),
              100 * median(vt));
  Json j = Json::object();
  j["device"] = dev.name();
  j["vertices"] = static_cast<long>(n);
  j["tets"] = static_cast<long>(mesh.num_tets());
  j["seeds"] = st.seeds;
  j["amplitude"] = st.amplitude;
  j["runs"] = runs;
  j["median"] = summary_json(S);
  j["fig3_log_vertex_ratio"]["harmonic"] = log_histogram(orig.harmonic.initial.vertex_ratio);
  j["fig3_log_vertex_ratio"]["volume"] = log_histogram(orig.volume.final.vertex_ratio);
  std::filesystem::create_directories(std::filesystem::path(st.out).parent_path());
  write_json_file(st.out, j);
  std::printf("wrote %s\n", st.out.c_str());
  return 0;
} catch (const std::exception& e) {
  std::cerr << "vpm_bench_paper: " << e.what() << "\n";
  return 3;
}
