#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "support/process.hpp"
#include "support/shapes.hpp"
#include "map/moser_field.hpp"
#include "map/polish.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/polish.hpp"
#include "vpm/solver.hpp"
#include "vpm/topology.hpp"
#include "vpm/volume_map.hpp"
#include "vpm/volume_map_peers.hpp"

using namespace vpm;
namespace fs = std::filesystem;

namespace {

// Initial map of a small ellipsoid (1.8 : 1 : 0.6) with the conformal sphere map: ~50 % volume
// distortion (the equal-area default starts at ~17 %), fold-free: work for the rounds to do.
const InitialMapResult& ellipsoid_start() {
  static const InitialMapResult r = [] {
    auto host = Device::host();
    InitialMapOptions o;
    o.sphere_density = InitialMapOptions::SphereDensity::conformal;
    return initial_map(*host, test::ellipsoid_mesh(6), o);
  }();
  return r;
}

double max_boundary_radius_error(const Points& x, const Tets& t) {
  const auto mask = boundary_vertex_mask(static_cast<int>(x.rows()), boundary_faces(t));
  double e = 0;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    if (mask[i]) e = std::max(e, std::fabs(x.row(i).norm() - 1.0));
  return e;
}

int run_status(const std::string& cmd) {
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string tmp(const std::string& name) { return std::string(VPM_TEST_TMP) + "/vm_" + name; }

}  // namespace

TEST_CASE("volume map: a Moser round lowers the distortion, boundary slides on the sphere, host == device") {
  const InitialMapResult& im = ellipsoid_start();
  const DistortionPair d0 = volume_distortion(im.mesh.vertices, im.ball, im.mesh.tets);
  REQUIRE(d0.folds == 0);
  REQUIRE(d0.vertex > 0.2);
  Points host_result;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    Points ball = im.ball;
    VolumeMapOptions o;
    o.rounds = 1;
    o.polish_rounds = 0;
    const VolumeMapResult r = volume_preserving_map(*dev, im.mesh.vertices, im.mesh.tets, ball, o);
    REQUIRE(r.rounds.size() == 1);
    CHECK(r.rounds[0].kind == "moser");
    const DistortionPair d1 = volume_distortion(im.mesh.vertices, ball, im.mesh.tets);
    CHECK(d1.folds == 0);
    CHECK(r.final_folds == 0);
    CHECK(d1.vertex < 0.5 * d0.vertex);  // sign conventions: the round moves toward the targets
    CHECK(d1.tet < d0.tet);
    CHECK(r.final_vertex_mean_abs_dev == Approx(d1.vertex));
    CHECK(max_boundary_radius_error(ball, im.mesh.tets) < 1e-12);
    // the boundary slides: boundary vertices moved along the sphere
    const auto mask = boundary_vertex_mask(static_cast<int>(ball.rows()), boundary_faces(im.mesh.tets));
    double bmove = 0;
    for (Eigen::Index i = 0; i < ball.rows(); ++i)
      if (mask[i]) bmove = std::max(bmove, (ball.row(i) - im.ball.row(i)).norm());
    CHECK(bmove > 1e-3);
    CHECK(r.rounds.size() == 1);
    CHECK(to_json(r).find("rounds")->size() == 1);
    if (dev->is_host()) {
      host_result = ball;
      // the host-side advection of an OpenCL run is the same code as this one
    } else {
      CHECK(r.device_advection);
      CHECK(to_json(r).find("advection")->string() == "device");
      CHECK((ball - host_result).cwiseAbs().maxCoeff() < 1e-8);
    }
  }
}

TEST_CASE("volume map: rounds until the tolerance, every method fold-free") {
  const InitialMapResult& im = ellipsoid_start();
  auto host = Device::host();
  const DistortionPair d0 = volume_distortion(im.mesh.vertices, im.ball, im.mesh.tets);
  for (const char* method : {"moser", "paper", "vsem"}) {
    INFO("method " << method);
    const std::string name = method;
    Points ball = im.ball;
    VolumeMapOptions o;
    o.max_rounds = name == "moser" ? 4 : 6;
    const VolumeMapResult r =
        name == "moser" ? volume_preserving_map(*host, im.mesh.vertices, im.mesh.tets, ball, o)
                        : volume_map_peer(*host, im.mesh.vertices, im.mesh.tets, ball, o, {parse_volume_map_peer(name)});
    CHECK(r.method == name);
    const DistortionPair d1 = volume_distortion(im.mesh.vertices, ball, im.mesh.tets);
    CHECK(d1.folds == 0);
    CHECK(d1.vertex < d0.vertex);
    CHECK(!r.rounds.empty());
    CHECK(r.rounds.size() <= (name == "moser" ? 4u + o.polish_rounds : 6u));
    for (const auto& rd : r.rounds) CHECK(rd.folds == 0);
    for (const auto& rd : r.rounds) CHECK((rd.kind == name || (name == "moser" && rd.kind == "polish")));
    if (name == "moser") CHECK(d1.vertex < 0.4 * d0.vertex);
    if (name == "vsem") {
      // boundary frozen
      const auto mask = boundary_vertex_mask(static_cast<int>(ball.rows()), boundary_faces(im.mesh.tets));
      for (Eigen::Index i = 0; i < ball.rows(); ++i)
        if (mask[i]) REQUIRE((ball.row(i) - im.ball.row(i)).norm() == 0.0);
    }
  }
}

TEST_CASE("volume map: the Moser rounds hand over to the polish once within 5x the tolerance") {
  const InitialMapResult& im = ellipsoid_start();
  auto host = Device::host();
  int handed_near = 0;
  for (double tolerance : {0.01, 0.045, 0.06}) {
    INFO("tolerance " << tolerance);
    VolumeMapOptions o;  // rounds automatic
    o.tolerance = tolerance;
    o.polish_rounds = 2;
    Points x = im.ball;
    const VolumeMapResult r = volume_preserving_map(*host, im.mesh.vertices, im.mesh.tets, x, o);
    std::vector<double> moser;
    for (const auto& rd : r.rounds)
      if (rd.kind == "moser") moser.push_back(rd.vertex_mean_abs_dev);
    REQUIRE(!moser.empty());
    INFO("initial " << r.initial_vertex_mean_abs_dev << ", stop " << r.stop_reason);
    double prev = r.initial_vertex_mean_abs_dev;
    for (size_t k = 0; k + 1 < moser.size(); ++k) {  // each round followed by another was far and gaining
      INFO("moser round " << k + 1 << ": " << moser[k]);
      CHECK(moser[k] > 5 * tolerance);
      CHECK(moser[k] <= 0.8 * prev);
      prev = moser[k];
    }
    const double last = moser.back();
    if (r.stop_reason == "stalled") {
      CHECK(last > tolerance);
      CHECK((last <= 5 * tolerance || last > 0.8 * prev));
      handed_near += last <= 5 * tolerance && last <= 0.5 * prev;  // a rule waiting for a gain under half would have gone on
    }
    CHECK(volume_distortion(im.mesh.vertices, x, im.mesh.tets).folds == 0);
  }
  CHECK(handed_near > 0);
}

TEST_CASE("volume map: polish rounds lower the per-tet distortion left by the Moser rounds") {
  const InitialMapResult& im = ellipsoid_start();
  auto host = Device::host();
  Points a = im.ball, b = im.ball;
  VolumeMapOptions o;
  o.rounds = 2;
  o.polish_rounds = 0;
  volume_preserving_map(*host, im.mesh.vertices, im.mesh.tets, a, o);
  o.polish_rounds = 3;
  const VolumeMapResult r = volume_preserving_map(*host, im.mesh.vertices, im.mesh.tets, b, o);
  const DistortionPair da = volume_distortion(im.mesh.vertices, a, im.mesh.tets);
  const DistortionPair db = volume_distortion(im.mesh.vertices, b, im.mesh.tets);
  REQUIRE(r.rounds.size() >= 3);
  CHECK(r.rounds[2].kind == "polish");
  CHECK(db.folds == 0);
  CHECK(db.tet < 0.9 * da.tet);
  CHECK(max_boundary_radius_error(b, im.mesh.tets) < 1e-12);
}

TEST_CASE("volume map: the polish runs the longer CGLS when the Moser rounds stop far from the tolerance") {
  const InitialMapResult& im = ellipsoid_start();
  auto host = Device::host();
  VolumeMapOptions o;
  o.rounds = 1;  // one Moser round, then the polish from wherever it got
  o.polish_rounds = 2;
  o.polish_iterations = 20;
  o.polish_iterations_far = 70;
  for (double tolerance : {1e-4, 0.5}) {
    INFO("tolerance " << tolerance);
    o.tolerance = tolerance;
    Points x = im.ball;
    const VolumeMapResult r = volume_preserving_map(*host, im.mesh.vertices, im.mesh.tets, x, o);
    REQUIRE(r.rounds.size() >= 2);
    REQUIRE(r.rounds[0].kind == "moser");
    const bool far = r.rounds[0].vertex_mean_abs_dev > 5 * tolerance;
    CHECK(far == (tolerance < 0.01));
    for (size_t k = 1; k < r.rounds.size(); ++k) {
      CHECK(r.rounds[k].kind == "polish");
      CHECK(r.rounds[k].solver_iterations == (far ? 70 : 20));
    }
  }
}

TEST_CASE("volume map: short of the tolerance, the polish goes on while a round gains a tenth, up to 4x its rounds") {
  const InitialMapResult& im = ellipsoid_start();
  auto host = Device::host();
  VolumeMapOptions o;
  o.rounds = 1;
  o.polish_rounds = 1;
  o.polish_iterations = 20;
  o.polish_iterations_far = 20;
  o.tolerance = 1e-4;  // never reached: every polish round is short of it
  Points x = im.ball;
  const VolumeMapResult r = volume_preserving_map(*host, im.mesh.vertices, im.mesh.tets, x, o);
  REQUIRE(r.rounds.size() >= 2);
  const size_t polish = r.rounds.size() - 1;
  CHECK(polish >= 2);  // the first polish round gains far more than a tenth here
  CHECK(polish <= 4);
  double before = r.rounds[0].tet_mean_abs_dev;
  for (size_t k = 1; k < r.rounds.size(); ++k) {
    INFO("round " << k);
    CHECK(r.rounds[k].kind == "polish");
    // a round after the first polish one follows only a round that gained a tenth
    if (k >= 2) CHECK(r.rounds[k - 1].tet_mean_abs_dev < 0.9 * before);
    if (k >= 2) before = r.rounds[k - 1].tet_mean_abs_dev;
  }
  if (polish < 4 && !r.rounds.back().discarded)  // it stopped because the last round gained less
    CHECK(r.rounds.back().tet_mean_abs_dev >= 0.9 * r.rounds[r.rounds.size() - 2].tet_mean_abs_dev);
  CHECK(volume_distortion(im.mesh.vertices, x, im.mesh.tets).folds == 0);
  // within the tolerance, polish_rounds is the cap
  o.tolerance = 0.5;
  Points y = im.ball;
  const VolumeMapResult c = volume_preserving_map(*host, im.mesh.vertices, im.mesh.tets, y, o);
  CHECK(c.rounds.size() <= 2);
}

TEST_CASE("polish_volumes runs only polish rounds and never moves pinned vertices") {
  const InitialMapResult& im = ellipsoid_start();
  auto host = Device::host();
  const int n = static_cast<int>(im.ball.rows());
  Points x = im.ball;
  PolishOptions o;
  o.pinned.assign(static_cast<size_t>(n), 0);
  for (int v = 0; v < n; v += 7) o.pinned[static_cast<size_t>(v)] = 1;
  const VolumeMapResult r = polish_volumes(*host, im.mesh.vertices, im.mesh.tets, x, o);
  REQUIRE(!r.rounds.empty());
  for (const auto& round : r.rounds) CHECK(round.kind == "polish");
  CHECK(r.stop_reason == "polish_only");
  CHECK(r.final_tet_mean_abs_dev < r.initial_tet_mean_abs_dev);
  CHECK(volume_distortion(im.mesh.vertices, x, im.mesh.tets).folds == 0);
  int moved = 0;
  for (int v = 0; v < n; ++v) {
    if (o.pinned[static_cast<size_t>(v)]) CHECK(x.row(v) == im.ball.row(v));
    else moved += x.row(v) != im.ball.row(v);
  }
  CHECK(moved > n / 2);
  CHECK(max_boundary_radius_error(x, im.mesh.tets) < 1e-12);
  // pinned needs the right length; rounds >= 0, iterations >= 1
  Points y = im.ball;
  PolishOptions bad = o;
  bad.pinned.pop_back();
  CHECK_THROWS_WITH(polish_volumes(*host, im.mesh.vertices, im.mesh.tets, y, bad), Catch::Contains("pinned has"));
  bad = o;
  bad.rounds = -1;
  CHECK_THROWS_AS(polish_volumes(*host, im.mesh.vertices, im.mesh.tets, y, bad), InputError);
  bad = o;
  bad.iterations = 0;
  CHECK_THROWS_AS(polish_volumes(*host, im.mesh.vertices, im.mesh.tets, y, bad), InputError);
  bad = o;
  bad.min_gain = 1;
  CHECK_THROWS_WITH(polish_volumes(*host, im.mesh.vertices, im.mesh.tets, y, bad), Catch::Contains("min_gain"));
  CHECK(y == im.ball);
  // the steps end at the first that gains less than min_gain: short steps (3 CGLS iterations)
  // go on for longer and end lower when smaller gains are accepted
  auto polish_with = [&](double min_gain, Points& out) {
    PolishOptions g = o;
    g.iterations = 3;
    g.rounds = 40;
    g.min_gain = min_gain;
    out = im.ball;
    return polish_volumes(*host, im.mesh.vertices, im.mesh.tets, out, g);
  };
  Points a, b, c;
  const VolumeMapResult strict = polish_with(0.05, a), usual = polish_with(0.01, b), loose = polish_with(0, c);
  INFO("rounds " << strict.rounds.size() << " / " << usual.rounds.size() << " / " << loose.rounds.size());
  CHECK(strict.rounds.size() < usual.rounds.size());
  CHECK(usual.rounds.size() <= loose.rounds.size());
  CHECK(loose.final_tet_mean_abs_dev <= usual.final_tet_mean_abs_dev);
  CHECK(usual.final_tet_mean_abs_dev < strict.final_tet_mean_abs_dev);
  for (size_t k = 0; k + 1 < strict.rounds.size(); ++k)  // every round but the last gained 5 %
    CHECK(strict.rounds[k].tet_mean_abs_dev <=
          0.95 * (k ? strict.rounds[k - 1].tet_mean_abs_dev : strict.initial_tet_mean_abs_dev));
  // a topology built once by the caller gives the same polish, byte for byte; one of other tets
  // is refused
  const TetTopology topology = tet_topology(n, im.mesh.tets);
  PolishOptions given = o;
  given.topology = &topology;
  Points z = im.ball;
  polish_volumes(*host, im.mesh.vertices, im.mesh.tets, z, given);
  CHECK(z == x);
  const TetTopology other = tet_topology(n, im.mesh.tets.topRows(im.mesh.tets.rows() / 2));
  given.topology = &other;
  CHECK_THROWS_WITH(polish_volumes(*host, im.mesh.vertices, im.mesh.tets, y, given),
                    Catch::Contains("topology given is not of these tets"));
  // the iteration scaling: as given up to 30,000 tets, times cbrt(tets / 30,000) above
  CHECK(polish_iterations_for(10, 1000) == 10);
  CHECK(polish_iterations_for(10, 30000) == 10);
  CHECK(polish_iterations_for(10, 240000) == 20);
}

namespace {
// Up to `count` anchors in interior tets of `tets` (every fifth tet at most) that share no vertex, at
// barycentric weights that differ per anchor.
std::vector<VolumeAnchor> interior_anchors(const Tets& tets, int n, int count) {
  const auto boundary = boundary_vertex_mask(n, boundary_faces(tets));
  std::vector<char> used(static_cast<size_t>(n), 0);
  std::vector<VolumeAnchor> out;
  for (Eigen::Index t = 0; t < tets.rows() && static_cast<int>(out.size()) < count; t += 5) {
    bool ok = true;
    for (int k = 0; k < 4; ++k) ok = ok && !boundary[static_cast<size_t>(tets(t, k))] && !used[static_cast<size_t>(tets(t, k))];
    if (!ok) continue;
    VolumeAnchor a;
    const double w[4] = {0.1 + 0.01 * (t % 7), 0.2, 0.3, 0.4};
    double sum = 0;
    for (double x : w) sum += x;
    for (int k = 0; k < 4; ++k) {
      a.vertices[static_cast<size_t>(k)] = tets(t, k);
      a.weights[static_cast<size_t>(k)] = w[k] / sum;
      used[static_cast<size_t>(tets(t, k))] = 1;
    }
    out.push_back(a);
  }
  return out;
}

// `anchors` and two more that share vertices with them: a second point in the first anchor's
// tet, and a point in another interior tet through the second anchor's first vertex.
std::vector<VolumeAnchor> with_shared(std::vector<VolumeAnchor> anchors, const Tets& tets, int n) {
  const auto boundary = boundary_vertex_mask(n, boundary_faces(tets));
  VolumeAnchor same = anchors[0];
  same.weights = {0.4, 0.3, 0.2, 0.1};
  anchors.push_back(same);
  const int v = anchors[1].vertices[0];
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    bool through = false, interior = true, other = false;
    for (int k = 0; k < 4; ++k) {
      through = through || tets(t, k) == v;
      interior = interior && !boundary[static_cast<size_t>(tets(t, k))];
      other = other || std::find(anchors[1].vertices.begin(), anchors[1].vertices.end(), tets(t, k)) == anchors[1].vertices.end();
    }
    if (!through || !interior || !other) continue;
    VolumeAnchor a;
    for (int k = 0; k < 4; ++k) {
      a.vertices[static_cast<size_t>(k)] = tets(t, k);
      a.weights[static_cast<size_t>(k)] = 0.25;
    }
    anchors.push_back(a);
    break;
  }
  return anchors;
}

Eigen::Vector3d anchor_point(const VolumeAnchor& a, const Points& x) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) p += a.weights[static_cast<size_t>(k)] * x.row(a.vertices[static_cast<size_t>(k)]).transpose();
  return p;
}
}  // namespace

TEST_CASE("volume map: anchors (sharing vertices or not) stay in place while their vertices move, and give back more volume than pins") {
  // a ball mesh whose interior was moved by a smooth compressible displacement, as a flow's
  // discretisation error leaves it: the polish restores the volumes with 40 points held
  const TetMesh ball = test::smooth_ball_mesh(10);
  const int n = static_cast<int>(ball.vertices.rows());
  const auto bmask = boundary_vertex_mask(n, boundary_faces(ball.tets));
  Points moved = ball.vertices;
  for (int v = 0; v < n; ++v) {
    if (bmask[static_cast<size_t>(v)]) continue;
    const Eigen::RowVector3d p = ball.vertices.row(v);
    const double s = 1 - p.squaredNorm();
    moved.row(v) += 0.04 * s * Eigen::RowVector3d(std::sin(3 * p.y()), std::sin(4 * p.z()), std::sin(3 * p.x()));
  }
  const std::vector<VolumeAnchor> anchors = with_shared(interior_anchors(ball.tets, n, 40), ball.tets, n);
  REQUIRE(anchors.size() >= 32);
  for (auto& dev : test::devices()) {
    INFO(dev->description().name);
    PolishOptions o;
    o.place = ExecutionPlace::device;  // the kernels on an OpenCL device, the host loops on the host
    o.anchors = anchors;
    Points x = moved;
    const VolumeMapResult r = polish_volumes(*dev, ball.vertices, ball.tets, x, o);
    REQUIRE(!r.rounds.empty());
    CHECK(volume_distortion(ball.vertices, x, ball.tets).folds == 0);
    CHECK(r.final_tet_mean_abs_dev < 0.5 * r.initial_tet_mean_abs_dev);
    int vertices_moved = 0;
    for (const VolumeAnchor& a : anchors) {
      CHECK((anchor_point(a, x) - anchor_point(a, moved)).norm() < 1e-12);
      for (int v : a.vertices) vertices_moved += x.row(v) != moved.row(v);
    }
    CHECK(vertices_moved > 2 * static_cast<int>(anchors.size()));
    // the same points held by pinning their tets' vertices: 12 constraints each instead of 3
    PolishOptions p = o;
    p.anchors.clear();
    p.pinned.assign(static_cast<size_t>(n), 0);
    for (const VolumeAnchor& a : anchors)
      for (int v : a.vertices) p.pinned[static_cast<size_t>(v)] = 1;
    Points y = moved;
    const VolumeMapResult rp = polish_volumes(*dev, ball.vertices, ball.tets, y, p);
    INFO("tet mean |r-1|: start " << r.initial_tet_mean_abs_dev << ", anchors " << r.final_tet_mean_abs_dev
                                  << ", pins " << rp.final_tet_mean_abs_dev);
    CHECK(r.final_tet_mean_abs_dev < 0.8 * rp.final_tet_mean_abs_dev);
  }
  const InitialMapResult& im = ellipsoid_start();
  const std::vector<VolumeAnchor> ea = interior_anchors(im.mesh.tets, static_cast<int>(im.ball.rows()), 10);
  REQUIRE(ea.size() >= 5);
  // refused: on the boundary, pinned, weightless
  auto host = Device::host();
  const int ne = static_cast<int>(im.ball.rows());
  const auto boundary = boundary_vertex_mask(ne, boundary_faces(im.mesh.tets));
  PolishOptions o;
  o.anchors = ea;
  auto refused = [&](const PolishOptions& bad, const char* what) {
    Points y = im.ball;
    CHECK_THROWS_WITH(polish_volumes(*host, im.mesh.vertices, im.mesh.tets, y, bad), Catch::Contains(what));
    CHECK(y == im.ball);
  };
  PolishOptions bad = o;
  for (int v = 0; v < ne; ++v)
    if (boundary[static_cast<size_t>(v)]) {
      bad.anchors[0].vertices[0] = v;
      break;
    }
  refused(bad, "on the boundary");
  bad = o;
  bad.pinned.assign(static_cast<size_t>(ne), 0);
  bad.pinned[static_cast<size_t>(o.anchors[2].vertices[1])] = 1;
  refused(bad, "pinned");
  bad = o;
  bad.anchors[3].weights = {0, 0, 0, 0};
  refused(bad, "no weight");
}

// The polish's target volumes for the ellipsoid's initial map: the native tet volumes scaled to
// the ball's total.
Eigen::VectorXd polish_target(const InitialMapResult& im) {
  const Eigen::VectorXd v0 = tet_volumes(im.mesh.vertices, im.mesh.tets);
  return v0 / v0.sum() * tet_volumes(im.ball, im.mesh.tets).sum();
}

TEST_CASE("polish direction: the CGLS written once stops alike on host and device (no iterations, nothing can move)") {
  const InitialMapResult& im = ellipsoid_start();
  const Points& x = im.ball;
  const Tets& T = im.mesh.tets;
  const int n = static_cast<int>(x.rows());
  const std::vector<char> freedom = detail::polish_freedom(boundary_vertex_mask(n, boundary_faces(T)), true, {});
  const std::vector<char> fixed(static_cast<size_t>(n), detail::kPolishFixed);  // P A^T b = 0: gamma = 0
  const Eigen::VectorXd target = polish_target(im);
  auto cl = test::opencl_device();
  if (!cl) WARN("no OpenCL device: the device's stops not compared");
  const auto check = [&](const std::vector<char>& f, int iterations, int done) {
    std::vector<detail::PolishDirection> got = {detail::polish_direction_host(x, T, target, f, {}, iterations)};
    if (cl) got.push_back(detail::DevicePolisher(*cl, T, n, f, {}).direction(x, target, iterations));
    for (const detail::PolishDirection& d : got) {
      CHECK(d.iterations == done);
      CHECK(d.residual == Approx(1.0).epsilon(1e-12));  // r = b
      CHECK(d.dx.cwiseAbs().maxCoeff() == 0.0);
    }
  };
  check(freedom, 0, 0);  // asked for none
  check(fixed, 40, 0);   // nothing can move: stops before the first iteration
  // one iteration: the host's and the device's first steps agree, and both count it
  const detail::PolishDirection h1 = detail::polish_direction_host(x, T, target, freedom, {}, 1);
  CHECK(h1.iterations == 1);
  CHECK(h1.residual < 1.0);
  if (cl) {
    const detail::PolishDirection d1 = detail::DevicePolisher(*cl, T, n, freedom, {}).direction(x, target, 1);
    CHECK(d1.iterations == 1);
    CHECK(d1.residual == Approx(h1.residual).epsilon(1e-12));
    CHECK((d1.dx - h1.dx).cwiseAbs().maxCoeff() < 1e-12 * h1.dx.cwiseAbs().maxCoeff());
  }
}

TEST_CASE("polish direction: host and device agree, fixed vertices stay, sphere vertices move tangentially, anchors hold") {
  const InitialMapResult& im = ellipsoid_start();
  const Points& x = im.ball;
  const Tets& T = im.mesh.tets;
  const int n = static_cast<int>(x.rows());
  const Eigen::VectorXd target = polish_target(im);
  const auto boundary = boundary_vertex_mask(n, boundary_faces(T));
  std::vector<char> pinned(static_cast<size_t>(n), 0);
  for (int v = 0; v < n; v += 11) pinned[static_cast<size_t>(v)] = 1;
  std::vector<VolumeAnchor> anchors;  // on vertices that are not pinned
  for (const VolumeAnchor& a : with_shared(interior_anchors(T, n, 30), T, n)) {
    bool free = true;
    for (int v : a.vertices) free = free && !pinned[static_cast<size_t>(v)];
    if (free) anchors.push_back(a);
  }
  REQUIRE(anchors.size() >= 5);
  auto cl = test::opencl_device();
  for (bool slide : {true, false}) {
    INFO("slide " << slide);
    const std::vector<char> freedom = detail::polish_freedom(boundary, slide, pinned);
    const detail::PolishDirection h = detail::polish_direction_host(x, T, target, freedom, anchors, 40);
    CHECK(h.iterations == 40);
    CHECK(h.residual < 1.0);  // the step reduces the linearised residual
    for (int v = 0; v < n; ++v) {
      if (freedom[v] == detail::kPolishFixed) CHECK(h.dx.row(v).norm() == 0.0);
      if (freedom[v] == detail::kPolishTangent) CHECK(std::abs(h.dx.row(v).dot(x.row(v).normalized())) < 1e-12);
    }
    for (const VolumeAnchor& a : anchors) CHECK(anchor_point(a, h.dx).norm() < 1e-14 * h.dx.cwiseAbs().maxCoeff());
    if (!cl) {
      WARN("no OpenCL device: device polish not compared");
      continue;
    }
    // Same arithmetic: after a few iterations the directions agree to round-off. Later
    // iterates of CGLS amplify the different summation order (loss of orthogonality), so at
    // 40 iterations only the residual reached is compared.
    // Both reduction modes: per work item (CPU devices) and per work group (GPUs).
    for (bool group : {false, true}) {
      INFO("group reduce " << group);
      test::GroupReduceScope scope(*cl, group);
      detail::DevicePolisher dp(*cl, T, n, freedom, anchors);
      const detail::PolishDirection h8 = detail::polish_direction_host(x, T, target, freedom, anchors, 8);
      const detail::PolishDirection d8 = dp.direction(x, target, 8);
      CHECK(d8.iterations == 8);
      CHECK(d8.residual == Approx(h8.residual).epsilon(1e-10));
      CHECK((d8.dx - h8.dx).cwiseAbs().maxCoeff() < 1e-10 * h8.dx.cwiseAbs().maxCoeff());
      const detail::PolishDirection d = dp.direction(x, target, 40);  // buffers reused
      CHECK(d.iterations == 40);
      CHECK(d.residual == Approx(h.residual).epsilon(1e-3));
      CHECK(d.dx.allFinite());
      const detail::PolishDirection d2 = dp.direction(x, target, 40);
      CHECK(d2.dx == d.dx);
    }
  }
}

TEST_CASE("polish direction: holds keep their points from moving along their directions while the rest restores") {
  const InitialMapResult& im = ellipsoid_start();
  const Points& x = im.ball;
  const Tets& T = im.mesh.tets;
  const int n = static_cast<int>(x.rows());
  const Eigen::VectorXd target = polish_target(im);
  const std::vector<char> freedom =
      detail::polish_freedom(boundary_vertex_mask(n, boundary_faces(T)), true, std::vector<char>{});
  // a hold at the centroid of every 7th tet, each along its own direction
  std::vector<VolumeHold> holds;
  for (int t = 0; t < T.rows(); t += 7) {
    VolumeHold h;
    for (int k = 0; k < 4; ++k) {
      h.vertices[static_cast<size_t>(k)] = T(t, k);
      h.weights[static_cast<size_t>(k)] = 0.25;
    }
    h.direction = Eigen::Vector3d(std::cos(t), std::sin(t), std::cos(3.0 * t)).normalized();
    holds.push_back(h);
  }
  auto along = [&](const std::vector<VolumeHold>& hs, const Points& dx) {  // rms of d . sum w dx
    double s = 0;
    for (const VolumeHold& h : hs) {
      Eigen::Vector3d m = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) m += h.weights[static_cast<size_t>(k)] * dx.row(h.vertices[static_cast<size_t>(k)]).transpose();
      s += std::pow(h.direction.normalized().dot(m), 2);
    }
    return std::sqrt(s / static_cast<double>(hs.size()));
  };
  const detail::PolishDirection free = detail::polish_direction_host(x, T, target, freedom, {}, 40);
  std::vector<VolumeHold> firm = holds;
  for (VolumeHold& h : firm) h.direction *= 30;  // rows far heavier than the volume rows
  const detail::PolishDirection held = detail::polish_direction_host(x, T, target, freedom, {}, 40, firm);
  INFO("free " << along(holds, free.dx) << ", held " << along(holds, held.dx) << "; residual " << free.residual
               << " -> " << held.residual);
  CHECK(along(holds, held.dx) < 0.3 * along(holds, free.dx));  // measured 0.21 (40 CGLS iterations)
  CHECK(held.residual < 1.0);  // the volume rows still gain: the holds fix one direction at a few points
  // no holds: bit for bit the direction without the argument
  const detail::PolishDirection none = detail::polish_direction_host(x, T, target, freedom, {}, 40, {});
  CHECK(none.dx == free.dx);
  // the OpenCL polisher carries the holds as rows after the tets': the same direction to
  // round-off (8 iterations, as in the test above), in both reduction modes, with anchors too
  if (auto cl = test::opencl_device()) {
    const std::vector<VolumeAnchor> anchors = interior_anchors(T, n, 12);
    for (bool group : {false, true}) {
      INFO("group reduce " << group);
      test::GroupReduceScope scope(*cl, group);
      detail::DevicePolisher dp(*cl, T, n, freedom, anchors, firm);
      const detail::PolishDirection h8 = detail::polish_direction_host(x, T, target, freedom, anchors, 8, firm);
      const detail::PolishDirection d8 = dp.direction(x, target, 8);
      CHECK(d8.iterations == 8);
      CHECK(d8.residual == Approx(h8.residual).epsilon(1e-10));
      CHECK((d8.dx - h8.dx).cwiseAbs().maxCoeff() < 1e-10 * h8.dx.cwiseAbs().maxCoeff());
      CHECK(along(holds, dp.direction(x, target, 40).dx) < 0.3 * along(holds, free.dx));
    }
  } else {
    WARN("no OpenCL device: device polish with holds not compared");
  }
  // a hold's vertex out of range is refused
  PolishOptions po;
  po.holds = holds;
  po.holds[0].vertices[2] = n;
  Points y = x;
  CHECK_THROWS_WITH(polish_volumes(*Device::host(), im.mesh.vertices, T, y, po), Catch::Contains("out of range"));
}

TEST_CASE("volume map: --boundary fixed keeps the boundary vertices in place") {
  const InitialMapResult& im = ellipsoid_start();
  for (auto& dev : test::devices()) {
    Points ball = im.ball;
    VolumeMapOptions o;
    o.rounds = 1;
    o.boundary = MapBoundary::fixed;
    volume_preserving_map(*dev, im.mesh.vertices, im.mesh.tets, ball, o);
    const auto mask = boundary_vertex_mask(static_cast<int>(ball.rows()), boundary_faces(im.mesh.tets));
    for (Eigen::Index i = 0; i < ball.rows(); ++i)
      if (mask[i]) REQUIRE((ball.row(i) - im.ball.row(i)).norm() == 0.0);
    CHECK(volume_distortion(im.mesh.vertices, ball, im.mesh.tets).folds == 0);
  }
}

TEST_CASE("volume map: a folded start that cannot be untangled is refused with NumericalError") {
  // ball_mesh(2) keeps tets with four boundary vertices; with the boundary fixed no interior
  // vertex can repair them once two boundary vertices are swapped.
  const TetMesh m = test::ball_mesh(2);
  Points ball = m.vertices;
  const auto mask = boundary_vertex_mask(m.num_vertices(), boundary_faces(m.tets));
  int a = -1, b = -1;
  for (int t = 0; t < m.num_tets() && a < 0; ++t) {
    int nb = 0;
    for (int k = 0; k < 4; ++k) nb += mask[m.tets(t, k)];
    if (nb == 4) {
      a = m.tets(t, 0);
      b = m.tets(t, 1);
    }
  }
  REQUIRE(a >= 0);
  ball.row(a).swap(ball.row(b));
  REQUIRE(volume_distortion(m.vertices, ball, m.tets).folds > 0);
  auto host = Device::host();
  VolumeMapOptions o;
  o.rounds = 1;
  CHECK_THROWS_AS(volume_preserving_map(*host, m.vertices, m.tets, ball, o), NumericalError);
  CHECK_THROWS_WITH(volume_preserving_map(*host, m.vertices, m.tets, ball, o),
                    Catch::Contains("inverted tets"));
  // bad sizes are input errors
  Points wrong = ball.topRows(5);
  CHECK_THROWS_AS(volume_preserving_map(*host, m.vertices, m.tets, wrong, o), InputError);
  CHECK_THROWS_AS(parse_volume_map_peer("moser"), InputError);  // vpm's own rounds are not a peer
  CHECK_THROWS_AS(parse_map_boundary("free"), InputError);
}

TEST_CASE("vpm map: a map that misses --tolerance warns, says converged false, exits 4 past 2x") {
  const std::string vpm = VPM_BINARY;
  write_mesh(tmp("conv_in.vtu"), test::ellipsoid_mesh(4));
  const std::string err = tmp("conv_err.txt"), report = tmp("conv_report.json");
  auto json = [&] {
    std::ifstream in(report);
    std::stringstream ss;
    ss << in.rdbuf();
    return Json::parse(ss.str());
  };
  auto text = [&] {
    std::ifstream in(err);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  // the default tolerance is met: converged, exit 0, no warning
  REQUIRE(run_status(vpm + " map " + tmp("conv_in.vtu") + " -o " + tmp("conv_ok.vtu") + " --report " + report +
                     " --quiet 2> " + err) == 0);
  CHECK(json().find("converged")->boolean());
  CHECK(text().find("warning") == std::string::npos);
  // an unreachable tolerance: the map is written, the report says why, exit 4
  fs::remove(tmp("conv_out.vtu"));
  CHECK(run_status(vpm + " map " + tmp("conv_in.vtu") + " -o " + tmp("conv_out.vtu") + " --tolerance 1e-9 --report " +
                   report + " --quiet 2> " + err) == kExitNotConverged);
  CHECK(fs::exists(tmp("conv_out.vtu")));
  const Json j = json();
  CHECK_FALSE(j.find("converged")->boolean());
  CHECK(j.find("convergence")->find("reached")->number() > 1e-9);
  CHECK(!j.find("convergence")->find("reason")->string().empty());
  CHECK(text().find("vpm map: warning: not converged: vertex mean |r-1|") != std::string::npos);
  // --allow-partial keeps 0 and the warning; fixed --rounds are not checked against the tolerance
  CHECK(run_status(vpm + " map " + tmp("conv_in.vtu") + " -o " + tmp("conv_out.vtu") +
                   " --tolerance 1e-9 --allow-partial --quiet 2> " + err) == 0);
  CHECK(text().find("warning: not converged") != std::string::npos);
  CHECK(run_status(vpm + " map " + tmp("conv_in.vtu") + " -o " + tmp("conv_out.vtu") + " --tolerance 1e-9 --rounds 1 --report " +
                   report + " --quiet 2> " + err) == 0);
  CHECK(json().find("converged") == nullptr);
  CHECK_FALSE(json().find("convergence")->find("checked")->boolean());
}

TEST_CASE("vpm map: writes the ball mesh with fields and the report, refuses bad options") {
  const std::string vpm = VPM_BINARY;
  const TetMesh m = test::ellipsoid_mesh(4);
  write_mesh(tmp("in.vtu"), m);
  fs::remove(tmp("out.vtu"));
  fs::remove(tmp("report.json"));
  REQUIRE(run_status(vpm + " map " + tmp("in.vtu") + " -o " + tmp("out.vtu") + " --report " +
                     tmp("report.json") + " --quiet") == 0);
  const TetMesh out = read_mesh(tmp("out.vtu"));
  REQUIRE(out.num_vertices() >= m.num_vertices());
  const Field* op = out.find_point_field("original_position");
  REQUIRE(op != nullptr);
  // input vertices first, in input order
  CHECK((op->values.topRows(m.num_vertices()) - FieldValues(m.vertices)).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(out.find_point_field("vertex_volume_ratio") != nullptr);
  CHECK(out.find_cell_field("tet_volume_ratio") != nullptr);
  CHECK(inverted_tets(out.vertices, out.tets).empty());
  std::ifstream in(tmp("report.json"));
  std::stringstream ss;
  ss << in.rdbuf();
  const Json j = Json::parse(ss.str());
  for (const char* k : {"device", "input", "initial", "final", "rounds", "timings_s"}) CHECK(j.find(k) != nullptr);
  CHECK(j.find("final")->find("inverted_tets")->number() == 0);
  CHECK(j.find("final")->find("vertex_volume_ratio")->find("mean_abs_dev")->number() <
        j.find("initial")->find("vertex_volume_ratio")->find("mean_abs_dev")->number());
  CHECK(j.find("timings_s")->find("total") != nullptr);
  CHECK(j.find("volume_map")->find("preconditioner")->string() == "jacobi");  // auto, a small mesh
  CHECK(j.find("initial_map")->find("harmonic")->find("preconditioner")->string() == "jacobi");

  // the AMG preconditioner gives the same map (to the solver tolerance) with fewer iterations
  REQUIRE(run_status(vpm + " map " + tmp("in.vtu") + " -o " + tmp("out_amg.vtu") + " --report " +
                     tmp("report_amg.json") + " --preconditioner amg --quiet") == 0);
  std::ifstream in_amg(tmp("report_amg.json"));
  std::stringstream ss_amg;
  ss_amg << in_amg.rdbuf();
  const Json ja = Json::parse(ss_amg.str());
  const Json& va = *ja.find("volume_map");
  CHECK(va.find("preconditioner")->string() == "amg");
  CHECK(ja.find("initial_map")->find("harmonic")->find("preconditioner")->string() == "amg");
  const double first_jacobi = j.find("volume_map")->find("rounds")->at(0).find("solver_iterations")->number();
  const double first_amg = va.find("rounds")->at(0).find("solver_iterations")->number();
  CHECK(first_amg < 0.5 * first_jacobi);
  const TetMesh out_amg = read_mesh(tmp("out_amg.vtu"));
  REQUIRE(out_amg.num_vertices() == out.num_vertices());
  // not bit-identical: each solve stops at a different point inside its 1e-8 tolerance and the
  // rounds amplify that (measured 2e-3 of the radius), so compare the maps' quality
  CHECK((out_amg.vertices - out.vertices).cwiseAbs().maxCoeff() < 2e-2);
  const double vj = j.find("final")->find("vertex_volume_ratio")->find("mean_abs_dev")->number();
  const double vg = ja.find("final")->find("vertex_volume_ratio")->find("mean_abs_dev")->number();
  CHECK(vg < 1.2 * vj + 1e-4);
  CHECK(ja.find("final")->find("inverted_tets")->number() == 0);
  CHECK(run_status(vpm + " map " + tmp("in.vtu") + " -o " + tmp("bad.vtu") + " --preconditioner ilu 2>/dev/null") == 2);

  // --rounds 0 stops after the initial map
  REQUIRE(run_status(vpm + " map " + tmp("in.vtu") + " -o " + tmp("out0.vtu") + " --rounds 0 --quiet") == 0);
  // usage errors: exit 2, nothing written
  fs::remove(tmp("bad.vtu"));
  CHECK(run_status(vpm + " map " + tmp("in.vtu") + " -o " + tmp("bad.vtu") + " --method fast 2>/dev/null") == 2);
  CHECK(run_status(vpm + " map " + tmp("in.vtu") + " -o " + tmp("bad.vtu") + " --rounds x 2>/dev/null") == 2);
  CHECK(run_status(vpm + " map " + tmp("missing.vtu") + " -o " + tmp("bad.vtu") + " 2>/dev/null") == 2);
  CHECK(!fs::exists(tmp("bad.vtu")));
}

TEST_CASE("point location: walk, grid fallback and clamping give exact P1 transport on host and device") {
  // A constant field (grad = e, rho0 = 1) is interpolated exactly, so interior points translate
  // by exactly e over t in [0, 1]. Every point starts its walk in tet 0 (a corner), so long
  // walks end in the grid search.
  const TetMesh m = test::ball_mesh(10);
  const auto nbr = detail::tet_neighbors(m.tets);
  detail::MoserField f;
  detail::build_background(f, m.vertices, m.tets, nbr);
  const Eigen::Vector3d e(0.05, -0.03, 0.02);
  f.grad.assign(3 * static_cast<size_t>(m.num_vertices()), 0.0);
  for (int i = 0; i < m.num_vertices(); ++i)
    for (int c = 0; c < 3; ++c) f.grad[3 * i + c] = e(c);
  f.rho0.assign(static_cast<size_t>(m.num_vertices()), 1.0);
  const auto boundary = boundary_vertex_mask(m.num_vertices(), boundary_faces(m.tets));
  detail::AdvectParams p;
  p.steps = 8;
  p.slide = true;
  std::vector<Points> results;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    Points x = m.vertices;
    std::vector<int> hint(static_cast<size_t>(m.num_vertices()), 0);
    detail::AdvectStats st;
    if (dev->is_host()) {
      detail::advect_host(f, boundary, p, x, hint, &st);
    } else {
      detail::DeviceAdvector adv(*dev, m.tets, nbr, boundary);
      adv.set_field(f);
      adv.advect(p, x, hint, &st);
    }
    CHECK(st.grid_fallbacks > 0);
    CHECK(st.clamped > 0);  // boundary points on the sphere lie outside the inscribed polyhedron
    double err = 0;
    int checked = 0;
    for (int i = 0; i < m.num_vertices(); ++i) {
      if (boundary[i]) {
        CHECK(std::fabs(x.row(i).norm() - 1.0) < 1e-12);
        continue;
      }
      if (m.vertices.row(i).norm() > 0.8) continue;  // may reach the boundary layer
      err = std::max(err, (x.row(i).transpose() - m.vertices.row(i).transpose() - e).norm());
      ++checked;
    }
    CHECK(checked > 100);
    CHECK(err < 1e-12);
    results.push_back(x);
  }
  if (results.size() == 2) CHECK((results[0] - results[1]).cwiseAbs().maxCoeff() < 1e-12);
}

TEST_CASE("Moser field gradients (eq. 12-13): linear psi reproduced, host == device, inverses too") {
  // On a jittered ball a linear psi = a . x has the gradient a on every tet, so every interior
  // vertex average is a to round-off, boundary vertices keep a's tangential part (sliding) or
  // 0 (fixed). A nonlinear psi compares the device kernels with the host reference.
  const TetMesh m = test::jitter_interior(test::ball_mesh(8), 8, 0.2, 3);
  const int n = m.num_vertices();
  const auto nbr = detail::tet_neighbors(m.tets);
  detail::MoserField f;
  detail::build_background(f, m.vertices, m.tets, nbr);
  f.rho0.assign(static_cast<size_t>(n), 1.0);
  const auto boundary = boundary_vertex_mask(n, boundary_faces(m.tets));
  const Eigen::VectorXd vol = tet_volumes(m.vertices, m.tets);
  const Eigen::Vector3d a(0.3, -0.7, 0.2);
  Eigen::VectorXd lin(n), wavy(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = m.vertices.row(i).transpose();
    lin(i) = a.dot(p);
    wavy(i) = std::sin(3 * p.x()) * std::cos(2 * p.y()) + p.z() * p.z();
  }
  for (bool slide : {true, false}) {
    INFO("slide " << slide);
    const auto g = detail::vertex_gradients(m.tets, m.vertices, detail::tet_gradients(f, lin), vol, boundary, slide);
    double err = 0;
    for (int i = 0; i < n; ++i) {
      Eigen::Vector3d want = a;
      if (boundary[i]) {
        const Eigen::Vector3d nrm = m.vertices.row(i).transpose().normalized();
        want = slide ? Eigen::Vector3d(a - a.dot(nrm) * nrm) : Eigen::Vector3d::Zero();
      }
      err = std::max(err, (Eigen::Vector3d(g[3 * i], g[3 * i + 1], g[3 * i + 2]) - want).norm());
    }
    CHECK(err < 1e-12);
    const auto host = detail::vertex_gradients(m.tets, m.vertices, detail::tet_gradients(f, wavy), vol, boundary, slide);
    double scale = 0;
    for (double v : host) scale = std::max(scale, std::fabs(v));
    REQUIRE(scale > 0.5);
    for (auto& dev : test::devices()) {
      if (dev->is_host()) continue;
      INFO("device " << dev->name());
      detail::DeviceAdvector adv(*dev, m.tets, nbr, boundary);
      adv.set_field(f, wavy, m.vertices, slide);
      // the inverse matrices made on the device == the host's (relative to each tet's size)
      const std::vector<double> inv = adv.inverses();
      REQUIRE(inv.size() == f.inv.size());
      double inv_diff = 0;
      for (size_t k = 0; k < inv.size(); ++k)
        inv_diff = std::max(inv_diff, std::fabs(inv[k] - f.inv[k]) / (1.0 + std::fabs(f.inv[k])));
      CHECK(inv_diff < 1e-12);
      const std::vector<double> d = adv.gradients();
      REQUIRE(d.size() == host.size());
      double diff = 0;
      for (size_t k = 0; k < d.size(); ++k) diff = std::max(diff, std::fabs(d[k] - host[k]));
      CHECK(diff < 1e-12 * scale);
    }
  }
}

TEST_CASE("volume map: the field's gradients on the device give the host-gradient map") {
  // advection = device computes the Moser field's gradients next to the advection (as on GPUs);
  // automatic on a CPU device keeps them on the host. One Moser round, no polish: the same
  // positions to round-off (whole maps amplify a 1e-12 difference in the field to ~1e-3 through
  // untangling and the early-stopped CGLS, docs/volume_map.md).
  const InitialMapResult& im = ellipsoid_start();
  for (auto& dev : test::devices()) {
    if (dev->is_host()) continue;
    INFO(dev->description().name);
    VolumeMapOptions o;
    o.rounds = 1;
    o.polish_rounds = 0;
    Points a = im.ball, b = im.ball;
    const VolumeMapResult ra = volume_preserving_map(*dev, im.mesh.vertices, im.mesh.tets, a, o);
    o.advection = ExecutionPlace::device;
    const VolumeMapResult rb = volume_preserving_map(*dev, im.mesh.vertices, im.mesh.tets, b, o);
    REQUIRE(ra.rounds.size() == rb.rounds.size());
    CHECK(ra.final_vertex_mean_abs_dev < 0.5 * ra.initial_vertex_mean_abs_dev);
    CHECK(rb.rounds.front().folds_before_untangle == ra.rounds.front().folds_before_untangle);
    CHECK(std::fabs(ra.final_vertex_mean_abs_dev - rb.final_vertex_mean_abs_dev) < 1e-10);
    CHECK((a - b).cwiseAbs().maxCoeff() < 1e-8);
    CHECK(volume_distortion(im.mesh.vertices, b, im.mesh.tets).folds == 0);
  }
}

TEST_CASE("vpm map: an input whose map cannot be made fold-free exits 3 and writes nothing") {
  // bent_mesh(3): a 270-degree C whose conformal boundary map flips triangles (docs/design.md 4.2:
  // appendages defeat the conformal start); since the progressive sphere start it is mapped, and
  // the output must then be fold-free.
  const std::string vpm = VPM_BINARY;
  write_mesh(tmp("bent.vtu"), test::bent_mesh(3));
  fs::remove(tmp("bent_out.vtu"));
  const int rc = run_status(vpm + " map " + tmp("bent.vtu") + " -o " + tmp("bent_out.vtu") +
                            " --quiet 2> " + tmp("bent.err"));
  if (rc == 3) {
    CHECK(!fs::exists(tmp("bent_out.vtu")));
    std::ifstream in(tmp("bent.err"));
    std::string msg((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    CHECK(msg.find("numerical failure") != std::string::npos);
  } else {
    REQUIRE(rc == 0);
    const TetMesh out = read_mesh(tmp("bent_out.vtu"));
    CHECK(inverted_tets(out.vertices, out.tets).empty());
  }
}

TEST_CASE("volume map: the initial map's Poisson solver handed on gives the same map and one built on other tets is ignored") {
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    InitialMapOptions io;
    io.sphere_density = InitialMapOptions::SphereDensity::conformal;
    const InitialMapResult im = initial_map(*dev, test::ellipsoid_mesh(5), io);
    REQUIRE(im.poisson);
    CHECK(im.poisson->laplacian().tets() == im.mesh.tets);
    VolumeMapOptions o;
    o.max_rounds = 2;
    o.polish_rounds = 1;
    Points own = im.ball, reused = im.ball, other = im.ball;
    volume_preserving_map(*dev, im.mesh.vertices, im.mesh.tets, own, o);
    o.poisson = im.poisson;
    volume_preserving_map(*dev, im.mesh.vertices, im.mesh.tets, reused, o);
    CHECK((reused - own).cwiseAbs().maxCoeff() == 0.0);
    const TetMesh small = test::ellipsoid_mesh(4);
    o.poisson = std::make_shared<PoissonSolver>(*dev, small.num_vertices(), small.tets);
    volume_preserving_map(*dev, im.mesh.vertices, im.mesh.tets, other, o);
    CHECK((other - own).cwiseAbs().maxCoeff() == 0.0);
    CHECK(o.poisson->laplacian().num_tets() == small.num_tets());
  }
}
