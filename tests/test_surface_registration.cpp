// Area-preserving landmark registration on the sphere (vpm/surface_registration.hpp).
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <random>

#include "map/surface_area.hpp"
#include "register/dense_surface.hpp"
#include "support/devices.hpp"
#include "support/process.hpp"
#include "support/scratch.hpp"
#include "vpm/error.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/surface_map.hpp"
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
  CHECK(r.restore_rounds > 0);
  CHECK(r.held_vertices == 24);  // a landmark at a vertex holds that vertex alone, not its star
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
    INFO("level " << level << ": " << r.flow_metrics.face_area_ratio.mean_abs_dev << ", repaired " << r.repaired_faces);
    if (r.repaired_faces == 0)  // nothing but the flow moved the points
      CHECK(r.metrics.face_area_ratio.mean_abs_dev == r.flow_metrics.face_area_ratio.mean_abs_dev);
    CHECK(r.flow_metrics.face_area_ratio.mean_abs_dev < 0.6 * prev);
    CHECK(r.landmark_max_error <= 1e-10);
    prev = r.flow_metrics.face_area_ratio.mean_abs_dev;
  }
  CHECK(prev < 0.012);
  // the restoration takes the rest down, the landmarks held still
  const TriSurface s = icosphere(5);
  const SurfaceRegistrationResult r = register_on_sphere(s.vertices, s.triangles, from, to);
  CHECK(r.metrics.face_area_ratio.mean_abs_dev < 0.5 * r.flow_metrics.face_area_ratio.mean_abs_dev);
  CHECK(r.held_vertices == from.rows());  // icosphere 3's vertices are icosphere 5's too: each held alone
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

namespace {

// The part of an icosphere below z = 0.3 stretched (a disk topologically), mapped to the unit disk.
TriSurface disk_map_of_cap(int level) {
  const TriSurface s = icosphere(level);
  std::vector<int> index(static_cast<size_t>(s.vertices.rows()), -1);
  std::vector<Eigen::RowVector3i> kept;
  TriSurface cap;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    bool in = true;
    for (int k = 0; k < 3; ++k) in = in && s.vertices(s.triangles(t, k), 2) < 0.3;
    if (in) kept.push_back(s.triangles.row(t));
  }
  std::vector<Eigen::RowVector3d> points;
  for (auto& t : kept)
    for (int k = 0; k < 3; ++k) {
      int& id = index[static_cast<size_t>(t(k))];
      if (id < 0) id = static_cast<int>(points.size()), points.push_back(s.vertices.row(t(k)).cwiseProduct(Eigen::RowVector3d(1.4, 1, 0.7)));
      t(k) = id;
    }
  cap.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) cap.vertices.row(static_cast<Eigen::Index>(i)) = points[i];
  cap.triangles.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t t = 0; t < kept.size(); ++t) cap.triangles.row(static_cast<Eigen::Index>(t)) = kept[t];
  cap.vertices = map_to_disk(cap).sphere;
  return cap;
}

// An area-preserving swirl of the disk: each circle of radius r turned by 0.3 sin(pi r).
Eigen::Vector3d swirl(const Eigen::Vector3d& x) {
  const double r = x.head<2>().norm();
  return Eigen::AngleAxisd(0.3 * std::sin(M_PI * r), Eigen::Vector3d::UnitZ()) * x;
}

}  // namespace

TEST_CASE("disk registration: landmarks exact, a swirl recovered, areas kept, the circle kept, edge landmarks refused") {
  const TriSurface d = disk_map_of_cap(4);
  Points from(12, 3), to(12, 3);
  int found = 0;
  for (Eigen::Index i = 0; i < d.vertices.rows() && found < 12; i += 97)
    if (d.vertices.row(i).norm() < 0.9) {
      from.row(found) = d.vertices.row(i);
      to.row(found++) = swirl(d.vertices.row(i).transpose()).transpose();
    }
  REQUIRE(found == 12);
  const SurfaceRegistrationResult r = register_in_disk(d.vertices, d.triangles, from, to);
  CHECK(r.landmark_max_error <= 1e-10);
  CHECK(r.restore_rounds > 0);
  CHECK(r.held_vertices == 12);  // a landmark at a vertex holds that vertex alone, not its star
  CHECK(r.metrics.flipped_faces == 0);
  CHECK(r.metrics.face_area_ratio.mean_abs_dev <= 0.005);
  CHECK(r.metrics.max_radius_error <= 1e-12);  // the boundary loop on the circle
  double moved = 0, error = 0;
  for (Eigen::Index i = 0; i < d.vertices.rows(); ++i) {
    const Eigen::Vector3d truth = swirl(d.vertices.row(i).transpose());
    moved += (truth - d.vertices.row(i).transpose()).norm();
    error += (truth - r.points.row(i).transpose()).norm();
    REQUIRE(r.points.row(i).head<2>().norm() <= 1 + 1e-12);
    REQUIRE(r.points(i, 2) == 0);
  }
  CHECK(error < 0.3 * moved);
  const SurfaceRegistrationResult self = register_in_disk(d.vertices, d.triangles, from, from);
  CHECK((self.points - d.vertices).cwiseAbs().maxCoeff() <= 1e-12);
  Points edge = to;
  edge.row(0) = Eigen::RowVector3d(1, 0, 0);
  CHECK_THROWS_WITH(register_in_disk(d.vertices, d.triangles, from, edge), Catch::Contains("strictly inside the unit disk"));
  CHECK_THROWS_AS(register_in_disk(2 * d.vertices, d.triangles, from, to), InputError);

  const std::string dir = vpm::test::fresh_dir("register_disk");
  write_surface(dir + "/disk.gii", d);
  {
    std::ofstream src(dir + "/src.csv"), dst(dir + "/dst.csv");
    src.precision(17);
    dst.precision(17);
    for (int i = 0; i < 12; ++i) {
      src << from(i, 0) << "," << from(i, 1) << ",0\n";
      dst << to(i, 0) << "," << to(i, 1) << ",0\n";
    }
  }
  const std::string cmd = std::string(VPM_BINARY) + " register " + dir + "/disk.gii -o " + dir + "/reg.vtp --landmarks " + dir +
                          "/src.csv --targets " + dir + "/dst.csv";
  REQUIRE(run_status(cmd + " --report " + dir + "/r.json 2>" + dir + "/err.txt") == 0);
  Json rep = Json::parse(slurp(dir + "/r.json"));
  CHECK(rep["domain"].string() == "disk");
  CHECK(rep["landmark_max_error"].number() <= 1e-6);  // the .gii holds the disk in float32
  CHECK(run_status(cmd + " --template " + dir + "/disk.gii --overlay x --template-overlay y 2>" + dir + "/err.txt") == 2);
  CHECK_THAT(slurp(dir + "/err.txt"), Catch::Contains("y: neither a file nor a point field"));
}

namespace {

// A smooth scalar of the plane with features at several scales (plane waves of wave numbers 3-8).
Eigen::VectorXd plane_features(const Points& x) {
  static const double waves[][4] = {{3, 1, 0.2, 1.0}, {-2, 4, 1.1, 0.8}, {5, 2, 2.3, 0.6}, {1, -6, 0.4, 0.5}, {6, 5, 1.7, 0.4}};
  Eigen::VectorXd v = Eigen::VectorXd::Zero(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (const auto& w : waves) v(i) += w[3] * std::sin(w[0] * x(i, 0) + w[1] * x(i, 1) + w[2]);
  return v;
}

Points swirled(const Points& x) {
  Points y(x.rows(), 3);
  for (Eigen::Index i = 0; i < x.rows(); ++i) y.row(i) = swirl(x.row(i).transpose()).transpose();
  return y;
}

double mean_distance(const Points& a, const Points& b) { return (a - b).rowwise().norm().mean(); }

}  // namespace

TEST_CASE("dense disk registration: a swirl recovered from a scalar, areas kept, the circle kept, identity on itself") {
  const TriSurface subject = disk_map_of_cap(4), tpl = disk_map_of_cap(5);  // two triangulations
  // the template is the subject's anatomy swirled: its value at swirl(y) is plane_features(y)
  const DiskTemplate t{swirled(tpl.vertices), tpl.triangles, plane_features(tpl.vertices)};
  const Points truth = swirled(subject.vertices);
  const Eigen::VectorXd f = plane_features(subject.vertices);
  const SurfaceRegistrationResult r = register_in_disk(subject.vertices, subject.triangles, f, t, Points(0, 3), Points(0, 3));
  const double before = mean_distance(subject.vertices, truth), after = mean_distance(r.points, truth);
  INFO("distance to the truth " << before << " -> " << after);
  CHECK(before > 0.05);
  CHECK(after < 0.35 * before);
  CHECK(!r.match.rotation_searched);  // correlated enough as they are
  CHECK(r.match.correlation_after > 0.99);
  CHECK(r.match.correlation_after > r.match.correlation_before);
  for (const SphereMatchLevel& l : r.match.levels) CHECK(l.mismatch_after < l.mismatch_before);
  CHECK(r.metrics.flipped_faces == 0);
  CHECK(r.metrics.face_area_ratio.mean_abs_dev <= 0.005);
  CHECK(r.metrics.max_radius_error <= 1e-12);  // the boundary loop on the circle
  CHECK((r.points.col(2).array() == 0).all());

  // with landmarks: exact, and the scalar still pulls the rest
  Points from(6, 3), to(6, 3);
  for (int i = 0, found = 0; found < 6; i += 53)
    if (subject.vertices.row(i).norm() < 0.9) from.row(found) = subject.vertices.row(i), to.row(found++) = truth.row(i);
  const SurfaceRegistrationResult both = register_in_disk(subject.vertices, subject.triangles, f, t, from, to);
  CHECK(both.landmark_max_error <= 1e-10);
  CHECK(both.metrics.flipped_faces == 0);
  CHECK(mean_distance(both.points, truth) < 0.5 * before);

  // a subject onto itself; a template turned by 100 degrees found by the rotation search
  const DiskTemplate same{subject.vertices, subject.triangles, f};
  const SurfaceRegistrationResult self = register_in_disk(subject.vertices, subject.triangles, f, same, Points(0, 3), Points(0, 3));
  CHECK((self.points - subject.vertices).cwiseAbs().maxCoeff() <= 1e-12);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(100 * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const DiskTemplate turned{tpl.vertices * R.transpose(), tpl.triangles, plane_features(tpl.vertices)};
  const SurfaceRegistrationResult found = register_in_disk(subject.vertices, subject.triangles, f, turned, Points(0, 3), Points(0, 3));
  CHECK(found.match.rotation_searched);
  CHECK(std::abs(std::atan2(found.match.rotation(1, 0), found.match.rotation(0, 0)) * 180 / M_PI - 100) < 2);
  CHECK(mean_distance(found.points, subject.vertices * R.transpose()) < 0.02);

  // the command line: the scalars as point fields of the .vtp files, a sphere template refused
  const std::string dir = vpm::test::fresh_dir("register_disk_dense");
  TriSurface s = subject, ts{t.disk, t.faces, {}, {}};
  s.point_data.push_back({"f", f, false});
  ts.point_data.push_back({"f", t.values, false});
  write_surface(dir + "/subject.vtp", s);
  write_surface(dir + "/template.vtp", ts);
  write_surface(dir + "/sphere.vtp", icosphere(2));
  const std::string cmd = std::string(VPM_BINARY) + " register " + dir + "/subject.vtp -o " + dir + "/reg.vtp --overlay f --template-overlay f";
  REQUIRE(run_status(cmd + " --template " + dir + "/template.vtp --report " + dir + "/r.json 2>" + dir + "/err.txt") == 0);
  Json rep = Json::parse(slurp(dir + "/r.json"));
  CHECK(rep["domain"].string() == "disk");
  CHECK(rep["registration"]["match"]["correlation_after"].number() == Approx(r.match.correlation_after).epsilon(1e-6));
  CHECK(rep["registration"]["final"]["flipped_faces"].number() == 0);
  CHECK(run_status(cmd + " --template " + dir + "/sphere.vtp 2>" + dir + "/err.txt") == 2);
  CHECK_THAT(slurp(dir + "/err.txt"), Catch::Contains("not in the unit disk"));

  CHECK_THROWS_AS(register_in_disk(subject.vertices, subject.triangles, f.head(10), t, from, to), InputError);
  for (double bad : {0.0, -1.0, std::nan("")}) {  // refused before any work (a negative width has no smoothing reach)
    SurfaceRegistrationOptions o;
    o.match.widths = {0.56, bad};
    CHECK_THROWS_WITH(register_in_disk(subject.vertices, subject.triangles, f, t, from, to, o), Catch::Contains("dense widths"));
    CHECK_THROWS_WITH(register_on_sphere(icosphere(2).vertices, icosphere(2).triangles, Eigen::VectorXd::LinSpaced(162, 0, 1),
                                         SphereTemplate{icosphere(2).vertices, icosphere(2).triangles, Eigen::VectorXd::LinSpaced(162, 0, 1)},
                                         Points(0, 3), Points(0, 3), o),
                      Catch::Contains("dense widths"));
  }
  CHECK_THROWS_WITH(register_in_disk(subject.vertices, subject.triangles, Eigen::VectorXd::Constant(f.size(), 2.0), t, Points(0, 3), Points(0, 3)),
                    Catch::Contains("constant"));
  CHECK_THROWS_AS(register_in_disk(subject.vertices, subject.triangles, f, DiskTemplate{2 * tpl.vertices, tpl.triangles, t.values},
                                   Points(0, 3), Points(0, 3)),
                  InputError);
}

TEST_CASE("dense disk registration: a crushed face given back its area, the held vertices and the circle kept") {
  using namespace vpm::detail;
  const TriSurface d = disk_map_of_cap(4);
  const Eigen::VectorXd a0 = face_areas(d.vertices, d.triangles);
  const SurfaceDomainMoves domain{SurfaceDomain::disk, loop_mask(static_cast<int>(d.vertices.rows()), d.triangles),
                                  std::vector<char>(static_cast<size_t>(d.vertices.rows()), 0)};
  auto interior = [&](Eigen::Index t) {
    for (int k = 0; k < 3; ++k)
      if (domain.boundary[static_cast<size_t>(d.triangles(t, k))] || d.vertices.row(d.triangles(t, k)).norm() > 0.6) return false;
    return true;
  };
  Eigen::Index t = 0;
  while (!interior(t)) ++t;
  // the disk's areas changed a little everywhere (r -> r^1.2, as a dense step's discrete shear
  // does), then the face's third corner pressed 93 % of the way onto the opposite edge's midpoint
  Points x = d.vertices;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    if (const double r = x.row(i).norm(); r > 0) x.row(i) *= std::pow(r, 0.2);
  const int a = d.triangles(t, 0), b = d.triangles(t, 1), c = d.triangles(t, 2);
  x.row(c) += 0.93 * (0.5 * (x.row(a) + x.row(b)) - x.row(c));
  REQUIRE(domain.flipped(x, d.triangles).empty());
  const double crushed = face_areas(x, d.triangles)(t) / a0(t);
  REQUIRE(crushed < kCrushedArea);
  SurfaceDomainMoves holding = domain;
  holding.fixed[static_cast<size_t>(a)] = 1;  // a landmark's corner stays where it is
  const double before = surface_metrics(d.vertices, x, d.triangles, SurfaceDomain::disk).face_area_ratio.mean_abs_dev;
  Points relieved = x;
  REQUIRE(relieve_areas(holding, a0, d.triangles, kReliefRounds, relieved));
  const SurfaceMetrics after = surface_metrics(d.vertices, relieved, d.triangles, SurfaceDomain::disk);
  INFO("face area mean |r-1| " << before << " -> " << after.face_area_ratio.mean_abs_dev << ", the crushed face " << crushed
                               << " -> " << face_areas(relieved, d.triangles)(t) / a0(t));
  CHECK(face_areas(relieved, d.triangles)(t) / a0(t) > 0.5);
  CHECK(after.face_area_ratio.mean_abs_dev < 0.5 * before);
  CHECK(after.flipped_faces == 0);
  CHECK(after.max_radius_error <= 1e-12);
  CHECK(relieved.row(a) == x.row(a));
  // nothing to give back on the input itself; a map with a flipped face is not touched
  Points same = d.vertices;
  CHECK(!relieve_areas(domain, a0, d.triangles, kReliefRounds, same));
  Points flipped = d.vertices;
  flipped.row(c) += 1.5 * (0.5 * (flipped.row(a) + flipped.row(b)) - flipped.row(c));
  REQUIRE(!domain.flipped(flipped, d.triangles).empty());
  const Points given = flipped;
  CHECK(!relieve_areas(domain, a0, d.triangles, kReliefRounds, flipped));
  CHECK(flipped == given);
}

TEST_CASE("flip repair: a sliver pushed past its edge comes back near its own area, held corners kept") {
  using namespace vpm::detail;
  const TriSurface s = icosphere(3);
  const Triangles& f = s.triangles;
  // the input: one face made a sliver (its third corner 95 % of the way to the opposite edge's
  // midpoint); the map: that corner pushed 5 % past the edge, the face flipped
  const int a = f(0, 0), b = f(0, 1), c = f(0, 2);
  const Eigen::RowVector3d mid = 0.5 * (s.vertices.row(a) + s.vertices.row(b));
  Points reference = s.vertices, x = s.vertices;
  reference.row(c) = (s.vertices.row(c) + 0.95 * (mid - s.vertices.row(c))).normalized();
  x.row(c) = (s.vertices.row(c) + 1.05 * (mid - s.vertices.row(c))).normalized();
  const Eigen::VectorXd a0 = face_areas(reference, f);
  std::vector<char> held(static_cast<size_t>(s.vertices.rows()), 0);
  held[static_cast<size_t>(a)] = held[static_cast<size_t>(b)] = 1;  // the edge's corners are landmarks
  const SurfaceDomainMoves domain{SurfaceDomain::sphere, {}, held};
  REQUIRE(domain.flipped(reference, f).empty());
  REQUIRE(domain.flipped(x, f) == std::vector<int>{0});
  Points kept = x, mean = x;
  CHECK(repair_flips(domain, f, a0, kept) == 1);
  CHECK(repair_flips(domain, f, Eigen::VectorXd(), mean) == 1);
  const double r_kept = face_areas(kept, f)(0) / a0(0), r_mean = face_areas(mean, f)(0) / a0(0);
  INFO("the sliver's area ratio: kept " << r_kept << ", neighbour mean " << r_mean);
  CHECK(domain.flipped(kept, f).empty());
  CHECK(domain.flipped(mean, f).empty());
  CHECK(r_kept > 1.0 / 3);
  CHECK(r_kept < 3);
  CHECK(r_mean > 10);  // the neighbours' mean gives the sliver a whole face's area
  CHECK(surface_metrics(reference, kept, f, SurfaceDomain::sphere).face_area_ratio.mean_abs_dev <
        0.5 * surface_metrics(reference, mean, f, SurfaceDomain::sphere).face_area_ratio.mean_abs_dev);
  CHECK(kept.row(a) == x.row(a));
  CHECK(kept.row(b) == x.row(b));
  CHECK(std::abs(kept.row(c).norm() - 1) < 1e-12);
  // a map without a flipped face is left as it is
  Points fine = reference;
  CHECK(repair_flips(domain, f, a0, fine) == 0);
  CHECK(fine == reference);
}

TEST_CASE("disk registration on host and device: the landmark flow and the dense steps' advections agree") {
  const TriSurface subject = disk_map_of_cap(3), tpl = disk_map_of_cap(4);
  const DiskTemplate t{swirled(tpl.vertices), tpl.triangles, plane_features(tpl.vertices)};
  const Points truth = swirled(subject.vertices);
  Points from(5, 3), to(5, 3);
  for (int i = 0, found = 0; found < 5; i += 37)
    if (subject.vertices.row(i).norm() < 0.9) from.row(found) = subject.vertices.row(i), to.row(found++) = truth.row(i);
  SurfaceRegistrationOptions o;
  o.restore_rounds = 0;  // the flows alone (the restoration is the host's polish)
  o.match.widths = {0.56, 0.28};
  o.match.iterations = 3;
  const Eigen::VectorXd f = plane_features(subject.vertices);
  Points host_landmarks, host_dense;
  SphereMatchReport host_match;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    const SurfaceRegistrationResult l = register_in_disk(subject.vertices, subject.triangles, from, to, o, dev.get());
    const SurfaceRegistrationResult d = register_in_disk(subject.vertices, subject.triangles, f, t, from, to, o, dev.get());
    for (const SurfaceRegistrationResult* r : {&l, &d}) {
      CHECK(r->landmark_max_error <= 1e-10);
      CHECK(r->metrics.flipped_faces == 0);
      CHECK(r->metrics.max_radius_error <= 1e-12);
    }
    REQUIRE(!d.match.levels.empty());
    CHECK(d.match.levels.back().iterations > 0);
    if (dev->is_host()) {
      host_landmarks = l.points, host_dense = d.points, host_match = d.match;
      CHECK((l.points - subject.vertices).cwiseAbs().maxCoeff() > 0.01);  // the flows moved the vertices
      continue;
    }
    // the same code (kernels/rbf_advect.clh, the disk's field) on both: round-off apart
    CHECK((l.points - host_landmarks).cwiseAbs().maxCoeff() < 1e-10);
    CHECK((d.points - host_dense).cwiseAbs().maxCoeff() < 1e-9);
    for (size_t k = 0; k < d.match.levels.size(); ++k) {
      CHECK(d.match.levels[k].iterations == host_match.levels[k].iterations);
      CHECK(d.match.levels[k].mismatch_after == Approx(host_match.levels[k].mismatch_after).epsilon(1e-9));
    }
  }
}
