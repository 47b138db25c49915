// Point location, comparison of subjects in the ball (label centroids, sampling, Dice), image
// resampling, the landmark CSV writer, map_to_ball and the `vpm demo` command end to end.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "support/process.hpp"
#include "support/shapes.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/collective.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/locate.hpp"
#include "vpm/registration.hpp"
#include "vpm/untangle.hpp"
#include "vpm/validate.hpp"

using namespace vpm;
namespace fs = std::filesystem;

namespace {

std::string tmp(const std::string& name) { return std::string(VPM_TEST_TMP) + "/collective_" + name; }

using test::run_status;

// Labels by octant sign of the tet centroid's x: 1 for x > 0, 2 otherwise.
std::vector<int> half_labels(const TetMesh& m) {
  std::vector<int> l(m.num_tets());
  for (int t = 0; t < m.num_tets(); ++t) {
    double x = 0;
    for (int k = 0; k < 4; ++k) x += m.vertices(m.tets(t, k), 0);
    l[t] = x > 0 ? 1 : 2;
  }
  return l;
}

}  // namespace

TEST_CASE("TetLocator finds the tet and barycentric coordinates of points inside, flags points outside") {
  const TetMesh m = test::ball_mesh(6);
  const TetLocator loc(m.vertices, m.tets);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Points pts(400, 3);
  std::vector<int> home(400);
  for (int i = 0; i < 400; ++i) {  // a random point of a random tet
    const int t = static_cast<int>(u(rng) * m.num_tets()) % m.num_tets();
    double w[4], s = 0;
    for (double& x : w) s += (x = u(rng) + 1e-3);
    Eigen::RowVector3d p = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) p += w[k] / s * m.vertices.row(m.tets(t, k));
    pts.row(i) = p;
    home[i] = t;
  }
  const std::vector<Location> found = loc.locate_all(pts);
  int same_tet = 0;
  for (int i = 0; i < 400; ++i) {
    const Location& l = found[i];
    REQUIRE(l.tet >= 0);
    CHECK(l.inside());
    Eigen::RowVector3d q = Eigen::RowVector3d::Zero();
    double s = 0;
    for (int k = 0; k < 4; ++k) {
      q += l.bary[k] * m.vertices.row(m.tets(l.tet, k));
      s += l.bary[k];
      CHECK(l.bary[k] >= -1e-12);
    }
    CHECK(std::abs(s - 1) < 1e-12);
    CHECK((q - pts.row(i)).norm() < 1e-12);  // the coordinates reproduce the point
    same_tet += l.tet == home[i];
  }
  CHECK(same_tet == 400);  // interior points of one tet belong to no other
  // single queries without a hint agree with the batch
  CHECK(loc.locate(pts.row(17).transpose()).tet == found[17].tet);
  // a point well outside the ball is not inside any tet
  const Location far = loc.locate(Eigen::Vector3d(3, 0, 0));
  CHECK_FALSE(far.inside());
  CHECK(far.min_bary < -0.1);
}

TEST_CASE("ball grid points fill the unit ball with the expected count") {
  const Points g = ball_grid_points(40);
  CHECK(g.rowwise().norm().maxCoeff() < 1.0);
  const double expected = (4.0 * M_PI / 3.0) / 8.0 * 40 * 40 * 40;
  CHECK(std::abs(g.rows() - expected) / expected < 0.02);
  CHECK_THROWS_AS(ball_grid_points(0), InputError);
}

TEST_CASE("label centroids: volume-weighted, they recombine to the mesh centroid, missing labels are NaN") {
  const TetMesh m = test::ellipsoid_mesh(6);
  const std::vector<int> lab = half_labels(m);
  const Points c = label_centroids(m.vertices, m.tets, lab, {1, 2, 99});
  CHECK(c(0, 0) > 0.2);
  CHECK(c(1, 0) < -0.2);
  CHECK(std::isnan(c(2, 0)));
  // sum_l V_l c_l = V c_total
  const Eigen::VectorXd v = tet_volumes(m.vertices, m.tets);
  double v1 = 0, v2 = 0;
  Eigen::RowVector3d total = Eigen::RowVector3d::Zero();
  for (int t = 0; t < m.num_tets(); ++t) {
    (lab[t] == 1 ? v1 : v2) += v(t);
    Eigen::RowVector3d ct = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) ct += 0.25 * m.vertices.row(m.tets(t, k));
    total += v(t) * ct;
  }
  CHECK((v1 * c.row(0) + v2 * c.row(1) - total).norm() < 1e-12 * (v1 + v2));
}

TEST_CASE("sampled labels follow the mesh, Dice is 1 for equal samplings and 0 for disjoint ones") {
  const TetMesh m = test::ball_mesh(8);
  const std::vector<int> lab = half_labels(m);
  const Points g = ball_grid_points(24);
  const std::vector<int> s = sample_labels(m.vertices, m.tets, lab, g);
  const double h = 2.0 / 8;  // mesh cell size: tets straddling x = 0 are within h of it
  int checked = 0;
  for (int i = 0; i < g.rows(); ++i)
    if (std::abs(g(i, 0)) > h && g.row(i).norm() < 0.9) {
      CHECK(s[i] == (g(i, 0) > 0 ? 1 : 2));
      ++checked;
    }
  CHECK(checked > 1000);
  // a point outside the mesh gets the outside label
  Points out(1, 3);
  out << 2.5, 0, 0;
  CHECK(sample_labels(m.vertices, m.tets, lab, out, -7)[0] == -7);

  const auto same = dice_overlap(s, s, {1, 2, 3});
  CHECK(same[0].dice == 1.0);
  CHECK(same[1].dice == 1.0);
  CHECK(same[2].dice == 1.0);  // empty in both
  std::vector<int> swapped(s);
  for (int& x : swapped) x = 3 - x;
  const auto none = dice_overlap(s, swapped, {1, 2});
  CHECK(none[0].dice == 0.0);
  CHECK(none[1].both == 0);
  // hand example: A = {0,1,2}, B = {1,2,3} -> 2*2/(3+3)
  const auto hand = dice_overlap({5, 5, 5, 0}, {0, 5, 5, 5}, {5});
  CHECK(hand[0].dice == Approx(2.0 / 3.0));
  CHECK_THROWS_AS(dice_overlap({1, 2}, {1}, {1}), InputError);
}

TEST_CASE("resample_image: identity keeps the image, a one-voxel shift moves it by one voxel") {
  Image im;
  im.dims = {6, 5, 4};
  im.affine = Eigen::Matrix4d::Identity();
  im.affine.topLeftCorner<3, 3>() = Eigen::Vector3d(2, 1.5, 1).asDiagonal();
  im.data.resize(im.size());
  for (size_t i = 0; i < im.size(); ++i) im.data[i] = static_cast<float>(i % 7 + i / 11);
  for (Interpolation mode : {Interpolation::nearest, Interpolation::linear}) {
    const Image same = resample_image(im, [](const Eigen::Vector3d& x) { return x; }, mode);
    CHECK(same.data == im.data);
    // pull(x) = x - one voxel along i (2 mm): out(i) = in(i - 1), 0 at i = 0
    const Image shifted =
        resample_image(im, [](const Eigen::Vector3d& x) { return Eigen::Vector3d(x.x() - 2, x.y(), x.z()); }, mode);
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 6; ++i)
          CHECK(shifted.at(i, j, k) == Approx(i == 0 ? 0.0f : im.at(i - 1, j, k)).margin(1e-5));
  }
  // half a voxel: trilinear averages neighbours, nearest picks one of them
  const Image half =
      resample_image(im, [](const Eigen::Vector3d& x) { return Eigen::Vector3d(x.x() + 1, x.y(), x.z()); },
                     Interpolation::linear);
  CHECK(half.at(2, 1, 1) == Approx(0.5 * (im.at(2, 1, 1) + im.at(3, 1, 1))));
}

TEST_CASE("write_landmarks_csv round-trips exactly through read_landmarks_csv") {
  Points p(3, 3);
  p << 0.1, -0.2, 1.0 / 3.0, 0, 0, 0, -0.7071067811865476, 0.7071067811865475, 1e-17;
  write_landmarks_csv(tmp("lm.csv"), p);
  const LandmarkFile back = read_landmarks_csv(tmp("lm.csv"), Points(0, 3));
  REQUIRE(back.points.rows() == 3);
  CHECK(back.points == p);
  CHECK(back.lines == std::vector<int>{2, 3, 4});
  CHECK_THROWS_AS(write_landmarks_csv(tmp("no_such_dir/lm.csv"), p), InputError);
}

TEST_CASE("map_to_ball: fold-free ball map with fields and the report contract, labels carried") {
  for (const auto& dev : test::devices()) {
    TetMesh m = test::ellipsoid_mesh(5);
    FieldValues lab(m.num_tets(), 1);
    const std::vector<int> hl = half_labels(m);
    for (int t = 0; t < m.num_tets(); ++t) lab(t, 0) = hl[t];
    m.set_cell_field("label", lab, true);
    const ValidationReport vr = validate_mesh(m, "ellipsoid");
    const BallMap bm = map_to_ball(*dev, m, vr, "ellipsoid");
    CHECK(bm.final.inverted_tets == 0);
    CHECK(inverted_tets(bm.mesh.vertices, bm.mesh.tets).empty());
    CHECK(bm.final.vertex_volume_ratio.mean_abs_dev < 0.5 * bm.initial.vertex_volume_ratio.mean_abs_dev);
    CHECK(bm.final.boundary_max_radius_error < 1e-12);
    CHECK(bm.mesh.find_point_field("original_position") != nullptr);
    CHECK(bm.mesh.find_point_field("vertex_volume_ratio") != nullptr);
    CHECK(bm.mesh.find_cell_field("tet_volume_ratio") != nullptr);
    const std::vector<int> out_lab = cell_labels(bm.mesh);
    CHECK(static_cast<int>(out_lab.size()) == bm.mesh.num_tets());
    for (const char* k : {"device", "input", "refined", "initial", "final", "rounds", "timings_s"})
      CHECK(to_json(bm).find(k) != nullptr);
    // --rounds 0: the initial map alone
    BallMapOptions o;
    o.volume.rounds = 0;
    const BallMap b0 = map_to_ball(*dev, m, vr, "ellipsoid", o);
    CHECK(b0.final.vertex_volume_ratio.mean_abs_dev == Approx(b0.initial.vertex_volume_ratio.mean_abs_dev));
    CHECK(!b0.volume_map);
    CHECK(to_json(b0).find("volume_map") == nullptr);
  }
}

TEST_CASE("vpm demo: meshes, maps and registers Colin27 and a deformed copy, Dice rises") {
  const std::string data = "/usr/share/mricron/templates/";
  if (!fs::exists(data + "ch2bet.nii.gz") || !fs::exists(data + "aal.nii.gz")) {
    WARN("mricron-data is not installed: vpm demo skipped");
    return;
  }
  const std::string out = tmp("demo");
  fs::remove_all(out);
  REQUIRE(run_status(std::string(VPM_BINARY) + " demo --out " + out + " --quiet > " + tmp("demo.txt")) == 0);
  for (const char* f : {"colin27.vtu", "colin27_ball.vtu", "subject.vtu", "subject_ball.vtu",
                        "subject_registered.vtu", "landmarks.csv", "targets.csv", "demo.json"})
    CHECK(fs::exists(out + "/" + f));
  const Json j = read_json_file(out + "/demo.json");
  for (const char* s : {"colin27", "subject"}) {
    const Json& sj = *j.find("subjects")->find(s);
    CHECK(sj.find("final")->find("inverted_tets")->number() == 0);
    CHECK(sj.find("final")->find("vertex_volume_ratio")->find("mean_abs_dev")->number() < 0.02);
  }
  const Json& reg = *j.find("registration");
  CHECK(reg.find("inverted_tets")->number() == 0);
  CHECK(reg.find("landmark_rms_error")->number() < 1e-6);
  CHECK(reg.find("dense")->find("iterations")->size() == 12);  // the standard preset
  // Dice in the subject's image space (Colin27's atlas carried onto the subject's voxels, one
  // rounding to a voxel grid): the registration brings every held-out region from about nothing
  // to most of its volume (measured 0.76-0.87)
  const Json& ov = *j.find("overlap");
  CHECK(ov.find("subject_voxels")->number() > 500000);
  const Json& held = *ov.find("held_out");
  REQUIRE(held.size() == 4);
  for (size_t i = 0; i < held.size(); ++i) {
    CHECK(held.at(i).find("dice_subject_before")->number() < 0.3);
    CHECK(held.at(i).find("dice_subject_after")->number() > 0.7);
  }
  // the registered mesh is the subject's ball mesh moved, fold-free, with its volume ratios
  const TetMesh r = read_mesh(out + "/subject_registered.vtu");
  CHECK(inverted_tets(r.vertices, r.tets).empty());
  REQUIRE(r.find_point_field("registration_vertex_volume_ratio") != nullptr);
  // the surfaces: both boundaries to the sphere without a flip, the subject's registered there (the
  // held-out cortical regions from nothing to most of their area: measured 0.76-0.87), the patch
  // to the disk
  const Json& surf = *j.find("surfaces");
  for (const char* s : {"colin27_sphere", "subject_sphere"}) {
    CHECK(surf.find(s)->find("final")->find("flipped_faces")->number() == 0);
    CHECK(surf.find(s)->find("final")->find("face_area_ratio")->find("mean_abs_dev")->number() <= 0.005);
  }
  CHECK(surf.find("registration_curvature")->find("final")->find("flipped_faces")->number() == 0);
  CHECK(surf.find("registration_curvature")->find("landmark_max_error")->number() <= 1e-10);
  const Json& sheld = *surf.find("held_out");
  REQUIRE(sheld.size() == 4);
  for (size_t i = 0; i < sheld.size(); ++i) {
    CHECK(sheld.at(i).find("dice_sphere_before")->number() < 0.3);
    CHECK(sheld.at(i).find("dice_sphere_landmarks")->number() > 0.7);
    CHECK(sheld.at(i).find("dice_sphere_curvature")->number() > 0.7);
    // the curvature alone: the two sphere maps differ by a rotation (measured 89 degrees), which
    // its rotation search finds first (measured Dice 0.81-0.86)
    CHECK(sheld.at(i).find("dice_sphere_curvature_alone")->number() > 0.7);
  }
  CHECK(surf.find("registration_curvature_alone")->find("match")->find("rotation_search")->find("angle_deg")->number() > 30);
  CHECK(surf.find("patch_disk")->find("final")->find("flipped_faces")->number() == 0);
  for (const char* f : {"colin27_sphere.vtp", "subject_sphere_registered.vtp", "colin27_patch_disk.vtp"})
    CHECK(fs::exists(out + "/" + f));
  // bad input: exit 2
  CHECK(run_status(std::string(VPM_BINARY) + " demo --out " + out + " --target-vertices 5 2>/dev/null") == 2);
  CHECK(run_status(std::string(VPM_BINARY) + " demo --out " + out + " --grid 48 2>/dev/null") == 2);  // a bench option
  CHECK(run_status(std::string(VPM_BINARY) + " demo --out " + out + " --data " + tmp("nothing") + " 2>/dev/null") == 2);
}

#ifdef VPM_BENCH_PAIRS_BINARY
TEST_CASE("vpm_bench_pairs: the ball measures and the ideal registration of the demo's pair") {
  const std::string data = "/usr/share/mricron/templates/";
  if (!fs::exists(data + "ch2bet.nii.gz") || !fs::exists(data + "aal.nii.gz")) {
    WARN("mricron-data is not installed: vpm_bench_pairs skipped");
    return;
  }
  const std::string out = tmp("pairs");
  fs::remove_all(out);
  REQUIRE(run_status(std::string(VPM_BENCH_PAIRS_BINARY) + " --out " + out + " --grid 48 --quiet > " + tmp("pairs.txt")) == 0);
  const Json j = read_json_file(out + "/demo.json");
  const Json& ov = *j.find("overlap");
  CHECK(ov.find("landmark_regions_mean_dice_after")->number() >
        ov.find("landmark_regions_mean_dice_before")->number() + 0.3);
  const Json& held = *ov.find("held_out");
  REQUIRE(held.size() == 4);
  for (size_t i = 0; i < held.size(); ++i)
    CHECK(held.at(i).find("dice_after")->number() > held.at(i).find("dice_before")->number());
  // the ideal registration (from the known deformation) aligns the held-out regions better than
  // the registration does, in the ball and more so in the subject's space (one rounding to a
  // voxel grid against two), and the registration is a short distance from it
  const Json& ideal = *j.find("ideal");
  const Json& iheld = *ideal.find("held_out");
  REQUIRE(iheld.size() == 4);
  for (size_t i = 0; i < iheld.size(); ++i) {
    CHECK(iheld.at(i).find("dice_image")->number() > 0.85);
    CHECK(iheld.at(i).find("dice_image")->number() > held.at(i).find("dice_image_after")->number());
    CHECK(held.at(i).find("dice_subject_after")->number() > held.at(i).find("dice_subject_before")->number() + 0.3);
    CHECK(iheld.at(i).find("dice_subject")->number() > 0.95);
    CHECK(iheld.at(i).find("dice_subject")->number() > iheld.at(i).find("dice_image")->number());
    CHECK(iheld.at(i).find("dice_subject")->number() > held.at(i).find("dice_subject_after")->number());
  }
  CHECK(ideal.find("boundary_vertices")->number() > 0);
  const double off = ideal.find("error_to_ideal")->find("mean")->number();
  CHECK(off > 0.005);
  CHECK(off < 0.05);
  const TetMesh r = read_mesh(out + "/subject_registered.vtu");
  const Field* err = r.find_point_field("error_to_ideal");
  REQUIRE(err != nullptr);
  CHECK(err->values.mean() == Approx(off).epsilon(1e-6));
  CHECK(run_status(std::string(VPM_BENCH_PAIRS_BINARY) + " --out " + out + " --grid 2 2>/dev/null") == 2);
}
#endif
