// Dense registration on the sphere (vpm/surface_registration.hpp, SphereMatchOptions) and point
// location on a sphere triangulation (vpm/locate.hpp, SphereLocator).
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>
#include <string>

#include "support/devices.hpp"
#include "support/process.hpp"
#include "support/scratch.hpp"
#include "vpm/curvature.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/locate.hpp"
#include "vpm/surface_registration.hpp"

using namespace vpm;
using vpm::test::run_status;
using vpm::test::slurp;

namespace {

// A known area-preserving deformation: each circle of latitude about `axis` rotated rigidly by
// an angle that depends on its height (Archimedes: areas kept).
Eigen::Vector3d twist(const Eigen::Vector3d& x) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, 2).normalized();
  const double h = x.dot(axis), theta = 0.25 * std::sin(M_PI * (h + 1) / 2 + 0.7);
  return Eigen::AngleAxisd(theta, axis) * x;
}

Points twisted(const Points& x) {
  Points y(x.rows(), 3);
  for (Eigen::Index i = 0; i < x.rows(); ++i) y.row(i) = twist(x.row(i).transpose()).transpose();
  return y;
}

// A smooth scalar with features at several scales in every direction (the "curvature" of the
// tests): plane waves of wave numbers 3 to 8.
double feature(const Eigen::Vector3d& p) {
  static const double waves[][5] = {{3, 0, 1, 0.2, 1.0}, {0, 4, -2, 1.1, 0.8}, {-2, 1, 5, 2.3, 0.7}, {5, -4, 0, 0.4, 0.5},
                                    {1, 6, 3, 1.7, 0.4}, {-6, -2, 4, 2.9, 0.4}, {4, 3, -6, 0.8, 0.3}, {7, 2, 3, 1.3, 0.3}};
  double f = 0;
  for (const auto& w : waves) f += w[4] * std::sin(w[0] * p.x() + w[1] * p.y() + w[2] * p.z() + w[3]);
  return f;
}

Eigen::VectorXd features(const Points& x) {
  Eigen::VectorXd v(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) v(i) = feature(x.row(i).transpose());
  return v;
}

// Mean angle between the rows of a and b.
double mean_angle(const Points& a, const Points& b) {
  double sum = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    sum += std::atan2(a.row(i).cross(b.row(i)).norm(), a.row(i).dot(b.row(i)));
  return sum / static_cast<double>(a.rows());
}

void write_curv(const std::string& path, const Eigen::VectorXd& v) {
  std::string bytes("\xFF\xFF\xFF", 3);
  auto be32 = [&bytes](std::uint32_t u) { for (int k = 24; k >= 0; k -= 8) bytes.push_back(static_cast<char>(u >> k)); };
  be32(static_cast<std::uint32_t>(v.size()));
  be32(0);
  be32(1);
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    const float x = static_cast<float>(v(i));
    std::uint32_t u;
    std::memcpy(&u, &x, 4);
    be32(u);
  }
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

TEST_CASE("sphere locator: every direction in the face whose cone holds it, coordinates reproduce it") {
  const TriSurface s = icosphere(3);
  const SphereLocator loc(s.vertices, s.triangles);
  std::mt19937 rng(5);
  std::normal_distribution<double> n;
  Points p(2000, 3);
  for (Eigen::Index i = 0; i < p.rows(); ++i) p.row(i) = Eigen::RowVector3d(n(rng), n(rng), n(rng)).normalized();
  const std::vector<SphereLocation> all = loc.locate_all(p);
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const SphereLocation& l = all[static_cast<size_t>(i)];
    REQUIRE(l.face >= 0);
    Eigen::Vector3d q = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      REQUIRE(l.bary[k] >= 0);
      q += l.bary[k] * s.vertices.row(s.triangles(l.face, k)).transpose();
    }
    REQUIRE(l.bary[0] + l.bary[1] + l.bary[2] == Approx(1));
    REQUIRE(q.normalized().cross(p.row(i).transpose()).norm() < 1e-12);  // on the ray through p
    // the same face from any hint (a walk across the sphere)
    REQUIRE(loc.locate(p.row(i).transpose(), static_cast<int>((i * 37) % s.triangles.rows())).face == l.face);
  }
}

TEST_CASE("dense sphere registration: a scalar's known area-preserving deformation recovered, areas kept, no flip") {
  const TriSurface subject = icosphere(4), tpl = icosphere(5);  // two triangulations
  // the template is the subject's anatomy deformed: its value at twist(y) is feature(y)
  const SphereTemplate t{twisted(tpl.vertices), tpl.triangles, features(tpl.vertices)};
  const Points truth = twisted(subject.vertices);
  const SurfaceRegistrationResult r =
      register_on_sphere(subject.vertices, subject.triangles, features(subject.vertices), t, Points(0, 3), Points(0, 3));
  const double before = mean_angle(subject.vertices, truth), after = mean_angle(r.points, truth);
  INFO("distance to the truth " << before << " -> " << after);
  CHECK(before > 0.05);
  // a scalar pins the motion across its level sets only: an area-preserving flow along them
  // (x × grad f) keeps it, so the truth is recovered up to such a drift where the scalar's
  // features do not cross
  CHECK(after < 0.35 * before);
  CHECK(r.match.correlation_before < 0.9);
  CHECK(r.match.correlation_after > 0.999);
  // the default levels 0.56 to 0.07 but the last, narrower than 1.5 mean edges (0.075) of 2,562 vertices
  REQUIRE(r.match.levels.size() == 3);
  CHECK(r.match.levels.back().width == 0.14);
  for (const SphereMatchLevel& l : r.match.levels) CHECK(l.mismatch_after < l.mismatch_before);
  CHECK(r.metrics.flipped_faces == 0);
  CHECK(r.metrics.face_area_ratio.mean_abs_dev <= 0.005);
  CHECK(r.metrics.max_radius_error <= 1e-12);
}

TEST_CASE("dense sphere registration: a subject onto itself is the identity, landmarks stay exact, bad scalars refused") {
  const TriSurface s = icosphere(4);
  const Eigen::VectorXd f = features(s.vertices);
  const SurfaceRegistrationResult self = register_on_sphere(s.vertices, s.triangles, f, {s.vertices, s.triangles, f}, Points(0, 3), Points(0, 3));
  CHECK((self.points - s.vertices).cwiseAbs().maxCoeff() <= 1e-12);

  const TriSurface tpl = icosphere(5);
  const SphereTemplate t{twisted(tpl.vertices), tpl.triangles, features(tpl.vertices)};
  Points from(6, 3), to(6, 3);
  for (int i = 0; i < 6; ++i) {
    from.row(i) = s.vertices.row(i * 97);
    to.row(i) = twist(from.row(i).transpose()).transpose();
  }
  const SurfaceRegistrationResult both = register_on_sphere(s.vertices, s.triangles, f, t, from, to);
  CHECK(both.landmark_max_error <= 1e-10);
  CHECK(both.metrics.flipped_faces == 0);
  CHECK(mean_angle(both.points, twisted(s.vertices)) < 0.6 * mean_angle(s.vertices, twisted(s.vertices)));

  CHECK_THROWS_AS(register_on_sphere(s.vertices, s.triangles, f.head(10), t, from, to), InputError);
  CHECK_THROWS_WITH(register_on_sphere(s.vertices, s.triangles, Eigen::VectorXd::Constant(f.size(), 2.0), t, Points(0, 3), Points(0, 3)),
                    Catch::Contains("constant"));
  CHECK_THROWS_AS(register_on_sphere(s.vertices, s.triangles, from, to.topRows(3)), InputError);
}

TEST_CASE("dense sphere registration without landmarks: a rotation between the sphere maps found first, or not at all") {
  const TriSurface subject = icosphere(4), tpl = icosphere(5);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(1.75, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  // the template is the subject's anatomy rotated by R (a sphere map is unique only up to one)
  const SphereTemplate t{tpl.vertices * R.transpose(), tpl.triangles, features(tpl.vertices)};
  const Points truth = subject.vertices * R.transpose();
  const SurfaceRegistrationResult r =
      register_on_sphere(subject.vertices, subject.triangles, features(subject.vertices), t, Points(0, 3), Points(0, 3));
  INFO("distance to the truth " << mean_angle(subject.vertices, truth) << " -> " << mean_angle(r.points, truth));
  REQUIRE(r.match.rotation_searched);
  CHECK(r.match.search_correlation_identity < 0.5);
  CHECK(r.match.search_correlation_best > 0.99);
  CHECK(Eigen::AngleAxisd(r.match.rotation * R.transpose()).angle() < 0.02);  // R found
  CHECK(r.match.correlation_after > 0.999);
  CHECK(mean_angle(r.points, truth) < 0.01);
  CHECK(r.metrics.flipped_faces == 0);
  CHECK(to_json(r, SurfaceRegistrationOptions{})["match"]["rotation_search"]["angle_deg"].number() == Approx(1.75 * 180 / M_PI).epsilon(0.01));
  // without the search the dense steps stay near the start
  SurfaceRegistrationOptions off;
  off.match.rotation_search = false;
  off.match.widths = {0.56, 0.28};
  const SurfaceRegistrationResult n =
      register_on_sphere(subject.vertices, subject.triangles, features(subject.vertices), t, Points(0, 3), Points(0, 3), off);
  CHECK(!n.match.rotation_searched);
  CHECK(mean_angle(n.points, truth) > 0.5);
  // with landmarks the rigid step sets the rotation: no search
  Points from(4, 3), to(4, 3);
  for (int i = 0; i < 4; ++i) from.row(i) = subject.vertices.row(i * 301), to.row(i) = truth.row(i * 301);
  SurfaceRegistrationOptions coarse;
  coarse.match.widths = {0.56, 0.28};
  CHECK(!register_on_sphere(subject.vertices, subject.triangles, features(subject.vertices), t, from, to, coarse).match.rotation_searched);
}

TEST_CASE("sphere registration on host and device: the landmark flow and the dense steps' advections agree") {
  const TriSurface s = icosphere(3), tpl = icosphere(4);
  const SphereTemplate t{twisted(tpl.vertices), tpl.triangles, features(tpl.vertices)};
  Points from(5, 3), to(5, 3);
  for (int i = 0; i < 5; ++i) {
    from.row(i) = s.vertices.row(i * 113);
    to.row(i) = twist(from.row(i).transpose()).transpose();
  }
  SurfaceRegistrationOptions o;
  o.restore_rounds = 0;  // the flows alone (the restoration is the host's polish)
  o.match.widths = {0.56, 0.28};
  o.match.iterations = 3;
  Points host_landmarks, host_dense;
  SphereMatchReport host_match;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    const SurfaceRegistrationResult l = register_on_sphere(s.vertices, s.triangles, from, to, o, dev.get());
    const SurfaceRegistrationResult d = register_on_sphere(s.vertices, s.triangles, features(s.vertices), t, from, to, o, dev.get());
    for (const SurfaceRegistrationResult* r : {&l, &d}) {
      CHECK(r->landmark_max_error <= 1e-10);
      CHECK(r->metrics.flipped_faces == 0);
      CHECK(r->metrics.max_radius_error <= 1e-12);
    }
    REQUIRE(d.match.levels.size() == 2);
    CHECK(d.match.levels[1].iterations > 0);
    if (dev->is_host()) {
      host_landmarks = l.points, host_dense = d.points, host_match = d.match;
      CHECK((l.points - s.vertices).cwiseAbs().maxCoeff() > 0.01);  // the flows moved the vertices
      continue;
    }
    // the same code (kernels/rbf_advect.clh) on both: round-off apart (the device may keep a few
    // centres below e^-32 that the host leaves out)
    CHECK((l.points - host_landmarks).cwiseAbs().maxCoeff() < 1e-10);
    CHECK((d.points - host_dense).cwiseAbs().maxCoeff() < 1e-9);
    for (size_t k = 0; k < d.match.levels.size(); ++k) {
      CHECK(d.match.levels[k].iterations == host_match.levels[k].iterations);
      CHECK(d.match.levels[k].mismatch_after == Approx(host_match.levels[k].mismatch_after).epsilon(1e-9));
    }
  }
}

TEST_CASE("vpm register SPHERE --template --overlay --template-overlay: the scalar matched, report, refusals exit 2") {
  const std::string dir = vpm::test::fresh_dir("register_sphere_dense");
  const std::string vpm_bin = VPM_BINARY;
  const TriSurface s = icosphere(4), tpl = icosphere(5);
  write_surface(dir + "/subject.gii", s);
  write_surface(dir + "/template.gii", TriSurface{twisted(tpl.vertices), tpl.triangles, {}, {}});
  write_curv(dir + "/lh.sulc", features(s.vertices));
  write_curv(dir + "/template.sulc", features(tpl.vertices));
  const std::string in = vpm_bin + " register " + dir + "/subject.gii -o " + dir + "/reg.gii";
  const std::string dense = " --template " + dir + "/template.gii --overlay " + dir + "/lh.sulc --template-overlay " + dir + "/template.sulc";
  REQUIRE(run_status(in + dense + " --report " + dir + "/r.json 2>" + dir + "/err.txt") == 0);
  Json r = Json::parse(slurp(dir + "/r.json"));
  CHECK(r["input"]["landmarks"].number() == 0);
  CHECK(r["registration"]["match"]["correlation_after"].number() > 0.99);
  CHECK(r["registration"]["match"]["levels"].size() == 3);
  CHECK(r["registration"]["final"]["flipped_faces"].number() == 0);
  const TriSurface out = read_surface(dir + "/reg.gii");
  CHECK(mean_angle(out.vertices, twisted(s.vertices)) < 0.35 * mean_angle(s.vertices, twisted(s.vertices)));
  // the scalars as point fields of .vtp inputs (vpm map SURFACE -o S.vtp --overlays lh.sulc)
  TriSurface sv = s, tv{twisted(tpl.vertices), tpl.triangles, {}, {}};
  sv.point_data.push_back({"sulc", features(s.vertices), false});
  tv.point_data.push_back({"sulc", features(tpl.vertices), false});
  write_surface(dir + "/subject.vtp", sv);
  write_surface(dir + "/template.vtp", tv);
  const std::string vtp = vpm_bin + " register " + dir + "/subject.vtp -o " + dir + "/reg2.gii --template " + dir + "/template.vtp";
  REQUIRE(run_status(vtp + " --overlay sulc --template-overlay sulc --report " + dir + "/r2.json 2>" + dir + "/err.txt") == 0);
  CHECK(Json::parse(slurp(dir + "/r2.json"))["registration"]["match"]["correlation_after"].number() ==
        Approx(r["registration"]["match"]["correlation_after"].number()).epsilon(1e-3));
  CHECK(run_status(vtp + " --overlay curv --template-overlay sulc 2>" + dir + "/err.txt") == 2);
  CHECK_THAT(slurp(dir + "/err.txt"), Catch::Contains("curv: neither a file nor a point field") && Catch::Contains("sulc"));
  // an overlay of the wrong length, --overlay without --template, a missing template overlay
  write_curv(dir + "/short.sulc", features(s.vertices).head(100));
  CHECK(run_status(in + " --template " + dir + "/template.gii --overlay " + dir + "/short.sulc --template-overlay " + dir +
                   "/template.sulc 2>" + dir + "/err.txt") == 2);
  CHECK_THAT(slurp(dir + "/err.txt"), Catch::Contains("short.sulc: 100 values") && Catch::Contains("2562 vertices"));
  CHECK(run_status(in + " --overlay " + dir + "/lh.sulc 2>" + dir + "/err.txt") == 2);
  CHECK_THAT(slurp(dir + "/err.txt"), Catch::Contains("--overlay needs --template"));
  CHECK(run_status(in + " --template " + dir + "/template.gii --overlay " + dir + "/lh.sulc 2>" + dir + "/err.txt") == 2);
  CHECK_THAT(slurp(dir + "/err.txt"), Catch::Contains("--template-overlay"));
}

TEST_CASE("mean curvature: 1/R on a sphere of radius R, the sign with the faces' orientation") {
  TriSurface s = icosphere(5);
  s.vertices *= 2.0;
  const Eigen::VectorXd h = mean_curvature(s);
  // within 1 % at the regular vertices, 15 % at the icosahedron's twelve of valence 5 (the area a
  // third of the faces' is not the vertex's Voronoi area there)
  int off = 0;
  for (Eigen::Index i = 0; i < h.size(); ++i) {
    REQUIRE(std::abs(h(i) - 0.5) < 0.15 * 0.5);
    off += std::abs(h(i) - 0.5) > 0.01 * 0.5;
  }
  CHECK(off <= 12);
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) std::swap(s.triangles(t, 1), s.triangles(t, 2));  // inward
  CHECK(mean_curvature(s).maxCoeff() < -0.49);
}
