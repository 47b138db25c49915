// Area-preserving landmark registration on the sphere (vpm/surface_registration.hpp).
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <random>

#include "support/process.hpp"
#include "support/scratch.hpp"
#include "vpm/error.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/surface_registration.hpp"

using namespace vpm;
using vpm::test::run_status;
using vpm::test::slurp;

namespace {

// `count` vertices of `s` spread by index, and targets: each rotated by `rotation` and then
// moved by up to `reach` radians in a random tangent direction.
void landmarks_of(const TriSurface& s, int count, const Eigen::Matrix3d& rotation, double reach, unsigned seed,
                  Points& from, Points& to) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  from.resize(count, 3);
  to.resize(count, 3);
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p = s.vertices.row((i * 7919) % s.vertices.rows()).normalized();
    Eigen::Vector3d d(u(rng), u(rng), u(rng));
    d -= p * p.dot(d);
    const Eigen::Vector3d moved = (p + reach * d.normalized() * std::abs(u(rng))).normalized();
    from.row(i) = p.transpose();
    to.row(i) = (rotation * moved).transpose();
  }
}

}  // namespace

TEST_CASE("sphere registration: landmarks land on their targets, face areas kept, no face flipped") {
  const TriSurface s = icosphere(5);
  Points from, to;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  landmarks_of(s, 24, R, 0.15, 7, from, to);
  const SurfaceRegistrationResult r = register_on_sphere(s.vertices, s.triangles, from, to);
  CHECK(r.landmark_rms_error <= 1e-10);
  CHECK(r.landmark_max_error <= 1e-10);
  CHECK(r.flow_landmark_max_error < 1e-4);  // the RK4 steps alone come close already
  CHECK(r.metrics.flipped_faces == 0);
  CHECK(r.metrics.face_area_ratio.mean_abs_dev <= 0.005);
  CHECK(r.metrics.max_radius_error <= 1e-12);
  // the rigid step found the rotation the targets were made with, up to the perturbations
  CHECK(Eigen::AngleAxisd(r.rotation).angle() > 0.3);
  // the images of the landmarks moved (not a rigid motion alone)
  double moved = 0;
  for (int i = 0; i < from.rows(); ++i) moved = std::max(moved, (r.rotation * from.row(i).transpose() - to.row(i).transpose()).norm());
  CHECK(moved > 0.05);
}

TEST_CASE("sphere registration: the flow's area change halves as the mesh refines (the field is divergence-free)") {
  // a field with divergence would change areas by a fixed amount at every resolution; this one's
  // chord triangles miss its exact motion by their size only
  Points from, to;
  landmarks_of(icosphere(3), 12, Eigen::Matrix3d::Identity(), 0.2, 11, from, to);
  SurfaceRegistrationOptions flow_only;
  flow_only.restore_rounds = 0;
  double prev = 1;
  for (int level : {3, 4, 5}) {
    const TriSurface s = icosphere(level);
    const SurfaceRegistrationResult r = register_on_sphere(s.vertices, s.triangles, from, to, flow_only);
    INFO("level " << level << ": " << r.metrics.face_area_ratio.mean_abs_dev);
    CHECK(r.metrics.face_area_ratio.mean_abs_dev == r.flow_metrics.face_area_ratio.mean_abs_dev);
    CHECK(r.metrics.face_area_ratio.mean_abs_dev < 0.6 * prev);
    CHECK(r.landmark_max_error <= 1e-10);
    prev = r.metrics.face_area_ratio.mean_abs_dev;
  }
  CHECK(prev < 0.012);
  // the restoration takes the rest down, the landmarks' faces held still
  const TriSurface s = icosphere(5);
  const SurfaceRegistrationResult r = register_on_sphere(s.vertices, s.triangles, from, to);
  CHECK(r.metrics.face_area_ratio.mean_abs_dev < 0.5 * r.flow_metrics.face_area_ratio.mean_abs_dev);
  CHECK(r.held_vertices >= 3 * from.rows());
  CHECK(r.metrics.flipped_faces == 0);
}

TEST_CASE("sphere registration: a subject to itself is the identity, a rotation is the rotation") {
  const TriSurface s = icosphere(4);
  Points from, to;
  landmarks_of(s, 10, Eigen::Matrix3d::Identity(), 0, 3, from, to);
  const SurfaceRegistrationResult same = register_on_sphere(s.vertices, s.triangles, from, from);
  CHECK((same.points - s.vertices.rowwise().normalized()).cwiseAbs().maxCoeff() <= 1e-12);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(1.1, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  const Points turned = from * R.transpose();
  const SurfaceRegistrationResult rot = register_on_sphere(s.vertices, s.triangles, from, turned);
  const Points expected = s.vertices.rowwise().normalized() * R.transpose();
  CHECK((rot.points - expected).cwiseAbs().maxCoeff() <= 1e-9);
}

TEST_CASE("sphere registration: points off the sphere, unequal counts and antipodal pairs are refused") {
  const TriSurface s = icosphere(2);
  Points from, to;
  landmarks_of(s, 4, Eigen::Matrix3d::Identity(), 0.1, 5, from, to);
  Points off = from;
  off.row(2) *= 1.5;
  CHECK_THROWS_WITH(register_on_sphere(s.vertices, s.triangles, off, to), Catch::Contains("landmark 2: not on the unit sphere"));
  CHECK_THROWS_AS(register_on_sphere(s.vertices, s.triangles, from, to.topRows(3)), InputError);
  Points anti = from.topRows(1), target = -from.topRows(1);
  SurfaceRegistrationOptions no_rigid;
  no_rigid.rigid = false;
  CHECK_THROWS_WITH(register_on_sphere(s.vertices, s.triangles, anti, target, no_rigid), Catch::Contains("antipodal"));
  Points bad = s.vertices;
  bad(0, 1) += 0.01;
  CHECK_THROWS_WITH(register_on_sphere(bad, s.triangles, from, to), Catch::Contains("vertex 0"));
}

TEST_CASE("vpm register SPHERE: landmarks by vertex id onto targets, report, tet-only options and unmapped surfaces exit 2") {
  const std::string dir = vpm::test::fresh_dir("register_surface");
  const std::string vpm_bin = VPM_BINARY;
  const TriSurface s = icosphere(4);
  write_surface(dir + "/sphere.off", s);
  Points from, to;
  landmarks_of(s, 8, Eigen::Matrix3d::Identity(), 0.1, 9, from, to);
  {
    std::ofstream src(dir + "/src.csv"), dst(dir + "/dst.csv");
    src << "vertex_id\n";
    dst.precision(17);
    for (int i = 0; i < from.rows(); ++i) {
      src << (i * 7919) % s.vertices.rows() << "\n";
      dst << to(i, 0) << "," << to(i, 1) << "," << to(i, 2) << "\n";
    }
  }
  const std::string args = " --landmarks " + dir + "/src.csv --targets " + dir + "/dst.csv";
  REQUIRE(run_status(vpm_bin + " register " + dir + "/sphere.off -o " + dir + "/reg.vtp" + args + " --report " + dir +
                     "/r.json 2>" + dir + "/err.txt") == 0);
  Json r = Json::parse(slurp(dir + "/r.json"));
  CHECK(r["domain"].string() == "sphere");
  CHECK(r["input"]["landmarks"].number() == 8);
  CHECK(r["landmark_max_error"].number() <= 1e-10);
  CHECK(r["registration"]["final"]["flipped_faces"].number() == 0);
  CHECK(r["converged"].boolean());
  // the same registration as the library's (the .off file holds the sphere at its precision)
  const SurfaceRegistrationResult lib = register_on_sphere(s.vertices, s.triangles, from, to);
  CHECK(r["registration"]["final"]["face_area_ratio"]["mean_abs_dev"].number() ==
        Approx(lib.metrics.face_area_ratio.mean_abs_dev).epsilon(1e-2));
  // options of the ball's registration, a surface off the sphere, an output that is not a surface
  CHECK(run_status(vpm_bin + " register " + dir + "/sphere.off -o " + dir + "/x.vtp" + args + " --field steady 2>" + dir + "/err.txt") == 2);
  CHECK_THAT(slurp(dir + "/err.txt"), Catch::Contains("option --field: applies to tet meshes only"));
  TriSurface big = s;
  big.vertices *= 2;
  write_surface(dir + "/big.off", big);
  CHECK(run_status(vpm_bin + " register " + dir + "/big.off -o " + dir + "/x.vtp" + args + " 2>" + dir + "/err.txt") == 2);
  CHECK_THAT(slurp(dir + "/err.txt"), Catch::Contains("is not on the unit sphere") && Catch::Contains("vpm map SURFACE"));
  CHECK(run_status(vpm_bin + " register " + dir + "/sphere.off -o " + dir + "/x.vtu" + args + " 2>" + dir + "/err.txt") == 2);
  CHECK(!std::filesystem::exists(dir + "/x.vtp"));
}
