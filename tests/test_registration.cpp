#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "support/shapes.hpp"
#include "vpm/collective.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/metrics.hpp"
#include "vpm/locate.hpp"
#include "vpm/registration.hpp"

using namespace vpm;

namespace {

// n landmarks at random in the ball of radius 0.75 and targets moved by up to `shift` (fixed
// seed), targets kept inside radius 0.85.
void random_landmarks(int n, double shift, unsigned seed, Points& p, Points& q) {
  test::random_landmarks(n, seed, 0.75, shift, 0.85, shift, p, q);
}

}  // namespace

TEST_CASE("Kabsch recovers a rotation and never returns a reflection") {
  Points p, q;
  random_landmarks(8, 0.0, 1, p, q);
  const Eigen::Matrix3d r0 = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Points rotated = p * r0.transpose();
  CHECK((kabsch_rotation(p, rotated) - r0).norm() < 1e-12);
  // mirrored targets: the best proper rotation, det +1
  Points mirrored = p;
  mirrored.col(0) *= -1;
  const Eigen::Matrix3d r = kabsch_rotation(p, mirrored);
  CHECK(r.determinant() == Approx(1.0).epsilon(1e-12));
  CHECK((r * r.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-12);
}

TEST_CASE("pathlines: endpoints, analytic velocity, inside the ball, arcs on the sphere") {
  const Eigen::Vector3d p(0.5, 0.2, -0.1), q(-0.2, 0.6, 0.3);
  CHECK((pathline(p, q, 0) - p).norm() < 1e-15);
  CHECK((pathline(p, q, 1) - q).norm() < 1e-14);
  for (double t : {0.1, 0.37, 0.8}) {
    Eigen::Vector3d v;
    pathline(p, q, t, &v);
    const double h = 1e-6;
    const Eigen::Vector3d fd = (pathline(p, q, t + h) - pathline(p, q, t - h)) / (2 * h);
    CHECK((v - fd).norm() < 1e-8);
  }
  const Eigen::Vector3d a = Eigen::Vector3d(1, 1, 0).normalized(), b = Eigen::Vector3d(0, -1, 1).normalized();
  for (double t = 0; t <= 1; t += 0.125) {
    CHECK(pathline(a, b, t).norm() == Approx(1.0).epsilon(1e-13));  // w = 1: great circle
    CHECK(pathline(0.9 * a, 0.95 * b, t).norm() <= 0.95 + 1e-12);
  }
}

TEST_CASE("registration moves landmarks to targets, preserves volumes, keeps the sphere") {
  const TetMesh m = test::smooth_ball_mesh(8);
  Points p, q;
  random_landmarks(6, 0.1, 2, p, q);
  std::vector<Points> results;
  // The flow alone: host and device must agree to round-off (the volume restoration after it
  // amplifies round-off differences; it has its own test below).
  RegistrationOptions flow_only;
  flow_only.restore_volumes = false;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    Points x = m.vertices;
    const RegistrationResult r = register_landmarks(*dev, x, m.tets, p, q, flow_only);
    INFO(to_json(r).dump());
    CHECK(r.landmark_rms_error < 1e-5);
    CHECK(r.landmark_max_error < 1e-4);
    CHECK(r.max_normal_velocity < 1e-12);
    CHECK(r.boundary_drift < 1e-6);
    CHECK(r.inverted_tets == 0);
    const MapMetrics mm = map_metrics(*dev, m.vertices, x, m.tets);
    CHECK(mm.boundary_max_radius_error < 1e-12);
    // divergence-free flow: what remains is the discretisation error of the coarse tets
    // (measured 3.0 % per tet, 0.67 % per vertex at h ~ 0.25)
    CHECK(mm.tet_volume_ratio.mean_abs_dev < 0.04);
    CHECK(mm.vertex_volume_ratio.mean_abs_dev < 0.01);
    // the vertices did move (by more than the rotation alone would explain for the landmarks)
    CHECK((x - m.vertices).rowwise().norm().maxCoeff() > 0.05);
    results.push_back(x);
  }
  if (results.size() == 2) CHECK((results[0] - results[1]).cwiseAbs().maxCoeff() < 1e-10);
}

TEST_CASE("volume restoration after the flow lowers the distortion and keeps the landmarks") {
  const TetMesh m = test::smooth_ball_mesh(8);
  Points p, q;
  random_landmarks(6, 0.1, 2, p, q);
  std::vector<double> restored_tet;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    RegistrationOptions off;
    off.restore_volumes = false;
    Points xf = m.vertices, xr = m.vertices;
    const RegistrationResult rf = register_landmarks(*dev, xf, m.tets, p, q, off);
    const RegistrationResult rr = register_landmarks(*dev, xr, m.tets, p, q);
    INFO(to_json(rr).dump());
    REQUIRE(rr.report.restore.has_value());
    const MapMetrics mf = map_metrics(*dev, m.vertices, xf, m.tets);
    const MapMetrics mr = map_metrics(*dev, m.vertices, xr, m.tets);
    CHECK(mr.inverted_tets == 0);
    CHECK(mr.boundary_max_radius_error < 1e-12);
    CHECK(mr.tet_volume_ratio.mean_abs_dev < 0.8 * mf.tet_volume_ratio.mean_abs_dev);
    CHECK(mr.vertex_volume_ratio.mean_abs_dev < 0.8 * mf.vertex_volume_ratio.mean_abs_dev);
    // the landmarks keep their place: the material point of each moved landmark did not move
    // (held as an anchor of the polish: its tet's vertices may move, but not their barycentric
    // combination), and with it every vertex that was not restored moved
    const TetLocator loc(xf, m.tets);
    int tet_vertices_moved = 0;
    for (Eigen::Index i = 0; i < rf.landmarks_final.rows(); ++i) {
      const Location l = loc.locate(rf.landmarks_final.row(i).transpose());
      REQUIRE(l.inside());
      Eigen::RowVector3d p = Eigen::RowVector3d::Zero();
      for (int k = 0; k < 4; ++k) {
        p += l.bary[k] * xr.row(m.tets(l.tet, k));
        tet_vertices_moved += xr.row(m.tets(l.tet, k)) != xf.row(m.tets(l.tet, k));
      }
      CHECK((p - rf.landmarks_final.row(i)).norm() < 1e-12);
    }
    CHECK(rr.report.restore->anchored_landmarks + rr.report.restore->pinned_vertices / 4 >= 1);
    if (rr.report.restore->anchored_landmarks > 0) CHECK(tet_vertices_moved > 0);
    CHECK(rr.landmark_rms_error == rf.landmark_rms_error);
    restored_tet.push_back(mr.tet_volume_ratio.mean_abs_dev);
  }
  // The polish is a few early-stopped least-squares steps: round-off in its input changes its
  // result slightly, so host and device agree in distortion, not to round-off.
  if (restored_tet.size() == 2) CHECK(std::abs(restored_tet[0] - restored_tet[1]) < 5e-4);
}

TEST_CASE("volume distortion is discretisation error: it shrinks as the mesh is refined") {
  Points p, q;
  random_landmarks(6, 0.1, 2, p, q);
  auto host = Device::host();
  double mad[2];
  for (int k = 0; k < 2; ++k) {
    const TetMesh m = test::smooth_ball_mesh(k == 0 ? 6 : 12);
    Points x = m.vertices;
    RegistrationOptions opt;
    opt.width_factor = 1.0;  // a field both meshes resolve (width 0.49 vs h 0.33 and 0.17)
    opt.restore_volumes = false;  // the flow's own error (the restoration is tested above)
    register_landmarks(*host, x, m.tets, p, q, opt);
    mad[k] = map_metrics(*host, m.vertices, x, m.tets).tet_volume_ratio.mean_abs_dev;
  }
  INFO("tet mean |r-1|: h " << mad[0] << ", h/2 " << mad[1]);
  CHECK(mad[1] < 0.7 * mad[0]);
}

TEST_CASE("a pure rotation of the landmarks is recovered by the rigid step alone") {
  const TetMesh m = test::ball_mesh(4);
  Points p, q;
  random_landmarks(5, 0.0, 3, p, q);
  const Eigen::Matrix3d r0 = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  q = p * r0.transpose();
  auto host = Device::host();
  Points x = m.vertices;
  const RegistrationResult r = register_landmarks(*host, x, m.tets, p, q);
  CHECK((r.rotation - r0).norm() < 1e-12);
  CHECK(r.landmark_max_error < 1e-12);
  CHECK((x - m.vertices * r0.transpose()).cwiseAbs().maxCoeff() < 1e-12);
}

TEST_CASE("boundary modes: samples and none agree with the host reference on the device") {
  const TetMesh m = test::ball_mesh(5);
  Points p, q;
  random_landmarks(5, 0.12, 4, p, q);
  for (RegistrationBoundary mode : {RegistrationBoundary::Samples, RegistrationBoundary::None}) {
    INFO("boundary " << to_string(mode));
    RegistrationOptions opt;
    opt.boundary = mode;
    opt.restore_volumes = false;  // compare the flows (see the restoration test)
    opt.steps = 10;
    opt.boundary_samples = 100;
    opt.normal_check_samples = 500;
    std::vector<RegistrationResult> res;
    std::vector<Points> xs;
    for (auto& dev : test::devices()) {
      Points x = m.vertices;
      res.push_back(register_landmarks(*dev, x, m.tets, p, q, opt));
      xs.push_back(x);
    }
    CHECK(res[0].landmark_rms_error < 1e-3);
    CHECK(res[0].max_normal_velocity > 1e-6);  // not exactly tangent
    if (mode == RegistrationBoundary::None) CHECK(res[0].boundary_drift > 1e-4);
    if (xs.size() == 2) {
      CHECK((xs[0] - xs[1]).cwiseAbs().maxCoeff() < 1e-10);
      CHECK(res[1].max_normal_velocity == Approx(res[0].max_normal_velocity).epsilon(1e-8));
    }
  }
}

TEST_CASE("steady field (paper construction) and leave-one-out width") {
  const TetMesh m = test::ball_mesh(5);
  Points p, q;
  random_landmarks(5, 0.1, 5, p, q);
  RegistrationOptions opt;
  opt.steps = 20;
  opt.field = RegistrationField::Steady;
  opt.width_loo = true;
  auto host = Device::host();
  Points x = m.vertices;
  const RegistrationResult r = register_landmarks(*host, x, m.tets, p, q, opt);
  INFO(to_json(r).dump());
  CHECK(r.report.width_loo.size() == 6);
  CHECK(to_json(r).find("width_loo")->size() == 6);
  CHECK(r.landmark_rms_error < 0.02);
  CHECK(r.inverted_tets == 0);
  CHECK(r.max_normal_velocity < 1e-12);
}

TEST_CASE("host and device advection agree") {
  Points p, q;
  random_landmarks(8, 0.2, 6, p, q);
  RegistrationOptions opt;
  opt.steps = 12;
  const std::vector<DivFreeField> fields = registration_fields(p, q, 9.0, opt);
  REQUIRE(fields.size() == 25);
  Points x0(300, 3);
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-0.57, 0.57);
  for (int i = 0; i < 300; ++i) x0.row(i) << u(gen), u(gen), u(gen);
  Points host = x0;
  advect(*Device::host(), host, fields, opt.steps);
  // the landmark paths are trajectories of the flow
  Points lm = p;
  advect(*Device::host(), lm, fields, opt.steps);
  CHECK((lm - q).rowwise().norm().maxCoeff() < 1e-4);
  for (auto& dev : test::devices()) {
    Points d = x0;
    advect(*dev, d, fields, opt.steps);
    CHECK((d - host).cwiseAbs().maxCoeff() < 1e-12);
  }
}

TEST_CASE("bad input is refused with InputError") {
  const TetMesh m = test::ball_mesh(3);
  auto host = Device::host();
  Points p(2, 3), q(2, 3);
  p << 0.1, 0.2, 0.3, -0.3, 0.1, 0.0;
  q << 0.2, 0.2, 0.3, -0.3, 0.2, 0.0;
  Points x = m.vertices;
  CHECK_THROWS_AS(register_landmarks(*host, x, m.tets, p, q.topRows(1)), InputError);
  Points out = p;
  out(1, 0) = 1.5;
  CHECK_THROWS_WITH(register_landmarks(*host, x, m.tets, out, q), Catch::Contains("outside the unit ball"));
  Points qout = q;
  qout(0, 2) = 1.2;
  CHECK_THROWS_WITH(register_landmarks(*host, x, m.tets, p, qout), Catch::Contains("outside the unit ball"));
  Points dup(3, 3), dq(3, 3);
  dup << p, p.row(0);
  dq << q, q.row(1);
  CHECK_THROWS_WITH(register_landmarks(*host, x, m.tets, dup, dq), Catch::Contains("different target"));
  dq.row(2) = q.row(0);  // same landmark, same target: accepted
  CHECK_NOTHROW(register_landmarks(*host, x, m.tets, dup, dq));
  Points unmapped = 1.1 * m.vertices;
  CHECK_THROWS_WITH(register_landmarks(*host, unmapped, m.tets, p, q), Catch::Contains("not mapped"));
  Points onsphere = p;
  onsphere.row(0) = p.row(0).normalized();
  CHECK_THROWS_WITH(register_landmarks(*host, x, m.tets, onsphere, q), Catch::Contains("boundary sphere"));
}

TEST_CASE("a folding registration is refused with NumericalError and leaves the mesh unchanged") {
  // test::ball_mesh flattens tets at the corners of every interior shell: the same landmark
  // moves that fold nothing on test::smooth_ball_mesh(8) invert some of them.
  const TetMesh m = test::ball_mesh(8);
  Points p, q;
  random_landmarks(6, 0.15, 2, p, q);
  auto host = Device::host();
  RegistrationOptions opt;
  opt.untangle = false;
  Points x = m.vertices;
  CHECK_THROWS_WITH(register_landmarks(*host, x, m.tets, p, q, opt), Catch::Contains("folded"));
  CHECK(x == m.vertices);
  // with the default local untangling the same folds are repaired, landmarks untouched
  const RegistrationResult r = register_landmarks(*host, x, m.tets, p, q);
  CHECK(r.inverted_tets == 0);
  CHECK(r.report.folded_by_flow > 0);
  REQUIRE(r.report.untangle.has_value());
  CHECK(r.landmark_max_error < 1e-6);
  CHECK(map_metrics(*host, m.vertices, x, m.tets).inverted_tets == 0);
}

namespace {

std::string tmp(const std::string& name) { return std::string(VPM_TEST_TMP) + "/register_" + name; }

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

// Runs `vpm register ...` (stderr to `err`), returns the exit status.
int vpm_register(const std::string& args, const std::string& err) {
  const std::string cmd = std::string(VPM_BINARY) + " register " + args + " 2>" + err;
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

TEST_CASE("vpm register: registers a mapped mesh, writes fields and the report") {
  TetMesh m = test::smooth_ball_mesh(6);
  m.set_point_field("original_position", m.vertices);
  const std::string mesh = tmp("ball.vtu"), out = tmp("out.vtu"), report = tmp("report.json");
  write_mesh(mesh, m);
  // landmarks: a header, a vertex id and two coordinate lines; targets as coordinates
  const int interior = 3 + 7 * (3 + 7 * 3);  // the centre vertex of test::smooth_ball_mesh(6)
  write_text(tmp("src.csv"), "x,y,z\n" + std::to_string(interior) + "\n0.3,0.2,0.1\n-0.4, 0.1, 0.2\r\n\n");
  write_text(tmp("dst.csv"), "0.05,0.0,0.02\n0.35,0.25,0.1\n-0.42,0.05,0.25\n");
  std::filesystem::remove(out);
  const int rc = vpm_register(mesh + " -o " + out + " --landmarks " + tmp("src.csv") + " --targets " +
                                  tmp("dst.csv") + " --steps 20 --report " + report + " --quiet",
                              tmp("err.txt"));
  INFO(slurp(tmp("err.txt")));
  REQUIRE(rc == 0);
  const TetMesh r = read_mesh(out);
  REQUIRE(r.num_vertices() == m.num_vertices());
  CHECK(r.find_point_field("original_position") != nullptr);
  REQUIRE(r.find_point_field("vertex_volume_ratio") != nullptr);
  REQUIRE(r.find_cell_field("tet_volume_ratio") != nullptr);
  CHECK((r.vertices.row(interior) - Eigen::RowVector3d(0.05, 0.0, 0.02)).norm() < 1e-6);
  const Json j = Json::parse(slurp(report));
  for (const char* key : {"landmark_rms_error", "landmark_max_error", "max_normal_velocity",
                          "vertex_volume_ratio", "tet_volume_ratio", "inverted_tets", "timings_s"})
    CHECK(j.find(key) != nullptr);
  CHECK(j.find("landmark_rms_error")->number() < 1e-6);
  CHECK(j.find("inverted_tets")->number() == 0);
}

TEST_CASE("vpm register --template: atlas-region centroids as landmarks, held-out regions excluded") {
  // template: test::smooth_ball_mesh(6) labelled by octant; moving: the same mesh turned 6 degrees about z
  // and squeezed a little in z, so its region centroids sit away from the template's.
  TetMesh fixed = test::smooth_ball_mesh(6);
  FieldValues label(fixed.num_tets(), 1);
  for (int t = 0; t < fixed.num_tets(); ++t) {
    Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) c += fixed.vertices.row(fixed.tets(t, k)) / 4;
    label(t, 0) = 1 + (c(0) > 0) + 2 * (c(1) > 0) + 4 * (c(2) > 0);
  }
  fixed.set_cell_field("label", label, true);
  TetMesh moving = fixed;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(6 * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (int i = 0; i < moving.num_vertices(); ++i) {
    Eigen::Vector3d p = turn * moving.vertices.row(i).transpose();
    p(2) *= 1 - 0.03 * (1 - p.squaredNorm());  // a squeeze that keeps the sphere
    moving.vertices.row(i) = p.transpose();
  }
  moving.set_point_field("original_position", FieldValues(fixed.vertices));
  write_mesh(tmp("tmpl_fixed.vtu"), fixed);
  write_mesh(tmp("tmpl_moving.vtu"), moving);
  const std::string out = tmp("tmpl_out.vtu"), report = tmp("tmpl_report.json");
  for (const std::string& exclude : {std::string(), std::string(" --exclude-labels 1,8")}) {
    INFO(exclude);
    std::filesystem::remove(out);
    const int rc = vpm_register(tmp("tmpl_moving.vtu") + " -o " + out + " --template " + tmp("tmpl_fixed.vtu") +
                                    exclude + " --steps 10 --quiet --report " + report,
                                tmp("tmpl_err.txt"));
    INFO(slurp(tmp("tmpl_err.txt")));
    REQUIRE(rc == 0);
    const Json j = Json::parse(slurp(report));
    CHECK(j.find("input")->find("landmarks")->number() == (exclude.empty() ? 8 : 6));
    CHECK(j.find("landmark_rms_error")->number() < 1e-6);
    // the registered regions' centroids are the template's
    const TetMesh r = read_mesh(out);
    const RegionLandmarks after = region_landmarks(r, fixed);
    REQUIRE(after.labels.size() == 8);
    for (size_t i = 0; i < after.labels.size(); ++i) {
      const double err = (after.source.row(i) - after.target.row(i)).norm();
      const bool held_out = !exclude.empty() && (after.labels[i] == 1 || after.labels[i] == 8);
      if (!held_out) CHECK(err < 1e-3);  // the centroid of a moved region, not just its landmark
    }
  }
  // refused: both ways at once; a template without labels; a bad label list
  TetMesh plain = fixed;
  plain.cell_data.clear();
  write_mesh(tmp("tmpl_plain.vtu"), plain);
  write_text(tmp("tmpl_src.csv"), "0.1,0.2,0.3\n");
  const std::vector<std::pair<std::string, std::string>> bad = {
      {" --template " + tmp("tmpl_fixed.vtu") + " --landmarks " + tmp("tmpl_src.csv"), "both given"},
      {" --template " + tmp("tmpl_plain.vtu"), "label"},
      {" --template " + tmp("tmpl_fixed.vtu") + " --exclude-labels 1,x", "--exclude-labels: expected integer"},
      {" --exclude-labels 1", "missing --landmarks"},
  };
  for (const auto& [args, expect] : bad) {
    INFO(args);
    std::filesystem::remove(out);
    CHECK(vpm_register(tmp("tmpl_moving.vtu") + " -o " + out + args, tmp("tmpl_err.txt")) == 2);
    CHECK(slurp(tmp("tmpl_err.txt")).find(expect) != std::string::npos);
    CHECK(!std::filesystem::exists(out));
  }
}

TEST_CASE("vpm register: landmarks far from their targets after the flow warn and exit 4") {
  // one RK4 step for moves of up to 0.3: the flow misses the targets by about 2e-3
  TetMesh m = test::smooth_ball_mesh(6);
  m.set_point_field("original_position", FieldValues(m.vertices));
  write_mesh(tmp("few_steps.vtu"), m);
  write_text(tmp("few_src.csv"), "0.3,0.2,0.1\n-0.4,0.1,0.2\n0.1,-0.5,0.3\n0.0,0.2,-0.6\n");
  write_text(tmp("few_dst.csv"), "0.6,0.1,0.2\n-0.2,0.4,0.1\n0.3,-0.25,0.45\n0.2,0.1,-0.35\n");
  const std::string args = tmp("few_steps.vtu") + " -o " + tmp("few_out.vtu") + " --landmarks " + tmp("few_src.csv") +
                           " --targets " + tmp("few_dst.csv") + " --no-rigid --report " + tmp("few.json");
  CHECK(vpm_register(args + " --steps 1", tmp("few_err.txt")) == kExitNotConverged);
  CHECK(slurp(tmp("few_err.txt")).find("warning: not converged: landmark max error") != std::string::npos);
  CHECK(std::filesystem::exists(tmp("few_out.vtu")));
  const Json j = Json::parse(slurp(tmp("few.json")));
  CHECK_FALSE(j.find("converged")->boolean());
  CHECK(j.find("landmark_max_error")->number() > 1e-3);
  CHECK(vpm_register(args + " --steps 1 --allow-partial", tmp("few_err.txt")) == 0);
  // enough steps: converged
  CHECK(vpm_register(args + " --steps 20", tmp("few_err.txt")) == 0);
  CHECK(Json::parse(slurp(tmp("few.json"))).find("converged")->boolean());
}

TEST_CASE("vpm register: bad input exits 2 naming the file and line") {
  const TetMesh m = test::smooth_ball_mesh(4);
  const std::string mesh = tmp("ball4.vtu"), out = tmp("bad_out.vtu"), err = tmp("bad_err.txt");
  write_mesh(mesh, m);
  TetMesh scaled = m;
  scaled.vertices *= 1.2;
  write_mesh(tmp("unmapped.vtu"), scaled);
  write_text(tmp("ok.csv"), "0.1,0.2,0.3\n-0.2,0.1,0\n");
  write_text(tmp("ok_dst.csv"), "0.15,0.2,0.3\n-0.2,0.15,0\n");
  struct Case {
    std::string mesh, src, src_text, expect;
  };
  const std::vector<Case> cases = {
      {mesh, "short.csv", "0.1,0.2,0.3\n", "has 1 landmarks but"},
      {mesh, "text.csv", "x,y,z\n0.1,abc,0.3\n-0.2,0.1,0\n", "text.csv:2: 'abc' is not a number"},
      {mesh, "two.csv", "0.1,0.2\n-0.2,0.1,0\n", "two.csv:1: expected x,y,z or vertex_id, got 2"},
      {mesh, "outside.csv", "0.1,0.2,0.3\n1.2,0.1,0\n", "outside.csv:2: landmark (1.2, 0.1, 0) is outside the unit ball"},
      {mesh, "id.csv", "0.1,0.2,0.3\n100000\n", "id.csv:2: vertex id 100000 out of range"},
      {mesh, "dup.csv", "0.1,0.2,0.3\n0.1,0.2,0.3\n", "with a different target"},
      {mesh, "empty.csv", "x,y,z\n", "no landmarks"},
      {tmp("unmapped.vtu"), "ok.csv", "0.1,0.2,0.3\n-0.2,0.1,0\n", "not mapped to the unit ball"},
  };
  for (const auto& c : cases) {
    INFO(c.src);
    write_text(tmp(c.src), c.src_text);
    std::filesystem::remove(out);
    const int rc = vpm_register(c.mesh + " -o " + out + " --landmarks " + tmp(c.src) + " --targets " +
                                    tmp("ok_dst.csv"), err);
    const std::string msg = slurp(err);
    INFO(msg);
    CHECK(rc == 2);
    CHECK(msg.find(c.expect) != std::string::npos);
    CHECK(!std::filesystem::exists(out));
  }
  // the restoration's step length and rounds: in range, and not without the restoration; the
  // dense fit's hidden settings in range
  write_text(tmp("ok.csv"), "0.1,0.2,0.3\n-0.2,0.1,0\n");
  for (const auto& [extra, expect] : std::vector<std::pair<std::string, std::string>>{
           {" --restore-iterations 0", "--restore-iterations: must be positive"},
           {" --no-restore --restore-iterations 5", "the restoration is off"},
           {" --restore-rounds 0", "--restore-rounds: expected 1 to 1000"},
           {" --no-restore --restore-rounds 5", "--restore-rounds: the restoration is off"},
           {" --restore-min-gain 1", "--restore-min-gain: expected a fraction in [0, 1)"},
           {" --dense-ridge 0", "--dense-ridge: expected (0, 100]"},
           {" --dense-smoothing 5", "--dense-smoothing: expected (0, 4]"},
           {" --dense-centre-spacing 0.1", "--dense-centre-spacing: expected 0.25 to 4"}}) {
    INFO(extra);
    std::filesystem::remove(out);
    CHECK(vpm_register(mesh + " -o " + out + " --landmarks " + tmp("ok.csv") + " --targets " + tmp("ok_dst.csv") + extra,
                       err) == 2);
    CHECK(slurp(err).find(expect) != std::string::npos);
    CHECK(!std::filesystem::exists(out));
  }
  // a folding registration: exit 3, no output
  TetMesh sliver = test::ball_mesh(8);
  write_mesh(tmp("sliver.vtu"), sliver);
  Points p, q;
  random_landmarks(6, 0.15, 2, p, q);
  std::ostringstream src, dst;
  for (int i = 0; i < 6; ++i) {
    src.precision(17);
    dst.precision(17);
    src << p(i, 0) << "," << p(i, 1) << "," << p(i, 2) << "\n";
    dst << q(i, 0) << "," << q(i, 1) << "," << q(i, 2) << "\n";
  }
  write_text(tmp("fold_src.csv"), src.str());
  write_text(tmp("fold_dst.csv"), dst.str());
  const int rc = vpm_register(tmp("sliver.vtu") + " -o " + out + " --landmarks " + tmp("fold_src.csv") +
                                  " --targets " + tmp("fold_dst.csv") + " --no-untangle", err);
  INFO(slurp(err));
  CHECK(rc == 3);
  CHECK(!std::filesystem::exists(out));
}
