#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "support/shapes.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/mesh_image.hpp"
#include "map/sphere_steps.hpp"
#include "vpm/topology.hpp"

using namespace vpm;

namespace {
void check_map(const InitialMapResult& r, const TetMesh& input) {
  const TetMesh& m = r.mesh;
  REQUIRE(r.ball.rows() == m.num_vertices());
  // input vertices first, unchanged
  CHECK((m.vertices.topRows(input.num_vertices()) - input.vertices).norm() == 0.0);
  const Field* op = m.find_point_field("original_position");
  REQUIRE(op != nullptr);
  CHECK((op->values - FieldValues(m.vertices)).norm() == 0.0);
  // fold-free, boundary on the sphere, interior inside
  CHECK(inverted_tets(r.ball, m.tets).empty());
  const Triangles bf = boundary_faces(m.tets);
  CHECK(flipped_sphere_triangles(r.ball, bf) == 0);
  const auto b = boundary_vertex_mask(m.num_vertices(), bf);
  double err = 0, rmax = 0;
  for (int i = 0; i < m.num_vertices(); ++i) {
    if (b[i]) err = std::max(err, std::abs(r.ball.row(i).norm() - 1));
    else rmax = std::max(rmax, r.ball.row(i).norm());
  }
  CHECK(err < 1e-12);
  CHECK(rmax < 1.0);
  CHECK(count_four_boundary_tets(m.tets, b) == 0);
  CHECK(r.report.folds_after_untangle == 0);
  CHECK(to_json(r.report).find("folds_after_untangle")->number() == 0);
}
// The surface of a tube of radius r along `turns` turns of a helix (radius 1, pitch 1), capped at
// both ends by one vertex each (the last two vertices): n rings of m vertices, faces outward.
TriSurface helix_tube(double turns, double r, int n, int m) {
  const double len = 2 * M_PI * turns;
  auto centre = [](double u) { return Eigen::Vector3d(std::cos(u), std::sin(u), u / (2 * M_PI)); };
  Points v(n * m + 2, 3);
  for (int i = 0; i < n; ++i) {
    const double u = len * i / (n - 1);
    const Eigen::Vector3d t = (centre(u + 1e-6) - centre(u - 1e-6)).normalized();
    const Eigen::Vector3d nn(-std::cos(u), -std::sin(u), 0), b = t.cross(nn);
    for (int j = 0; j < m; ++j) {
      const double a = 2 * M_PI * j / m;
      v.row(i * m + j) = centre(u) + r * (std::cos(a) * nn + std::sin(a) * b);
    }
  }
  const Eigen::Vector3d t0 = (centre(1e-6) - centre(-1e-6)).normalized();
  const Eigen::Vector3d t1 = (centre(len + 1e-6) - centre(len - 1e-6)).normalized();
  v.row(n * m) = centre(0) - r * t0;
  v.row(n * m + 1) = centre(len) + r * t1;
  Triangles f(2 * (n - 1) * m + 2 * m, 3);
  Eigen::Index k = 0;
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j < m; ++j) {
      const int a = i * m + j, b = i * m + (j + 1) % m, c = a + m, d = b + m;
      f.row(k++) << a, b, d;
      f.row(k++) << a, d, c;
    }
  for (int j = 0; j < m; ++j) {
    f.row(k++) << n * m, (j + 1) % m, j;
    f.row(k++) << n * m + 1, (n - 1) * m + j, (n - 1) * m + (j + 1) % m;
  }
  double vol = 0;
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    vol += Eigen::Vector3d(v.row(f(t, 0))).dot(Eigen::Vector3d(v.row(f(t, 1))).cross(Eigen::Vector3d(v.row(f(t, 2)))));
  if (vol < 0) f.col(1).swap(f.col(2));
  return {v, f};
}
}  // namespace

TEST_CASE("edge split leaves no four-boundary-vertex tet and keeps the volume") {
  int centroid_splits = 0;
  for (const TetMesh& in : {test::cube_mesh(3), test::ball_mesh(4), test::bent_mesh(2), test::single_tet()}) {
    const SplitResult s = split_boundary_edges(in);
    centroid_splits += s.centroid_splits;
    const auto b = boundary_vertex_mask(s.mesh.num_vertices(), boundary_faces(s.mesh.tets));
    CHECK(s.four_boundary_tets_before > 0);
    CHECK(s.four_boundary_tets_after == 0);
    CHECK(count_four_boundary_tets(s.mesh.tets, b) == 0);
    const Eigen::VectorXd v = tet_volumes(s.mesh.vertices, s.mesh.tets);
    CHECK(v.minCoeff() > 0);
    CHECK(v.sum() == Approx(tet_volumes(in.vertices, in.tets).sum()).epsilon(1e-13));
    CHECK(s.mesh.num_vertices() == in.num_vertices() + s.inserted_vertices);
    // the boundary surface is unchanged: the same triangles, in the same order and orientation,
    // as the input's, which the result hands on
    CHECK(boundary_faces(s.mesh.tets) == boundary_faces(in.tets));
    CHECK(s.boundary == boundary_faces(s.mesh.tets));
    // inserted vertices are midpoints of their parents
    for (int i = in.num_vertices(); i < s.mesh.num_vertices(); ++i) {
      const auto p = s.parents[i];
      if (p[0] < 0) continue;
      CHECK(p[0] < i);
      CHECK(p[1] < i);
      CHECK((s.mesh.vertices.row(i) - 0.5 * (s.mesh.vertices.row(p[0]) + s.mesh.vertices.row(p[1]))).norm() < 1e-15);
    }
  }
  CHECK(centroid_splits > 0);  // both kinds of split were exercised
}

TEST_CASE("edge split carries cell and point fields") {
  TetMesh in = test::cube_mesh(2);
  FieldValues lab(in.num_tets(), 1);
  for (int i = 0; i < in.num_tets(); ++i) lab(i, 0) = i % 5;
  in.set_cell_field("label", lab, true);
  FieldValues px(in.num_vertices(), 1);
  px.col(0) = in.vertices.col(0);
  in.set_point_field("xcoord", px);
  const SplitResult s = split_boundary_edges(in);
  const Field* l = s.mesh.find_cell_field("label");
  REQUIRE(l);
  for (int i = 0; i < s.mesh.num_tets(); ++i) CHECK(l->values(i, 0) == lab(s.parent_tet[i], 0));
  const Field* x = s.mesh.find_point_field("xcoord");
  REQUIRE(x);
  CHECK((x->values.col(0) - s.mesh.vertices.col(0)).cwiseAbs().maxCoeff() < 1e-15);
}

TEST_CASE("sphere map of a closed surface: no flipped triangles, balanced") {
  const TetMesh m = test::ellipsoid_mesh(8);
  TriSurface s{m.vertices, boundary_faces(m.tets)};
  const SphereMapResult r = sphere_map(s);
  CHECK(r.flipped_triangles == 0);
  const auto b = boundary_vertex_mask(m.num_vertices(), s.triangles);
  for (int i = 0; i < m.num_vertices(); ++i)
    if (b[i]) CHECK(std::abs(r.sphere.row(i).norm() - 1) < 1e-14);
  CHECK(r.report.area_distortion_balanced < r.report.area_distortion_conformal + 1e-12);
}

namespace {
// Largest |log(sphere area share / input area share)| over the vertices (areas lumped: a third
// of each triangle's).
double max_abs_log_area(const Points& in, const Points& sp, const Triangles& f) {
  Eigen::VectorXd a = Eigen::VectorXd::Zero(in.rows()), b = Eigen::VectorXd::Zero(in.rows());
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const Eigen::Vector3d p0 = in.row(f(t, 0)), p1 = in.row(f(t, 1)), p2 = in.row(f(t, 2));
    const Eigen::Vector3d q0 = sp.row(f(t, 0)), q1 = sp.row(f(t, 1)), q2 = sp.row(f(t, 2));
    for (int j = 0; j < 3; ++j) {
      a(f(t, j)) += (p1 - p0).cross(p2 - p0).norm();
      b(f(t, j)) += (q1 - q0).cross(q2 - q0).norm();
    }
  }
  const double sa = a.sum(), sb = b.sum();
  double worst = 0;
  for (Eigen::Index i = 0; i < a.size(); ++i)
    if (a(i) > 0) worst = std::max(worst, std::abs(std::log((b(i) / sb) / (a(i) / sa))));
  return worst;
}
}  // namespace

TEST_CASE("equal-area sphere map: an elongated shape is not squeezed, nothing flips") {
  // a rod of aspect 6 and the C-shaped slab: the conformal map shrinks their ends exponentially
  TetMesh rod = test::box_mesh(24, 4, 4);
  rod.vertices.col(0) *= 6.0;
  for (const auto& [name, m] : {std::pair<const char*, TetMesh>{"rod", rod}, {"bent", test::bent_mesh(4)}}) {
    INFO(name);
    const TriSurface s{m.vertices, boundary_faces(m.tets)};
    InitialMapOptions conformal;
    conformal.sphere_density = InitialMapOptions::SphereDensity::conformal;
    const SphereMapResult c = sphere_map(s, conformal);
    const SphereMapResult a = sphere_map(s);  // area is the default
    REQUIRE(c.flipped_triangles == 0);
    CHECK(a.flipped_triangles == 0);
    CHECK(a.report.density_kept);
    CHECK(a.report.density_target == "area");
    CHECK(*a.report.density_steps > 0);
    CHECK(a.report.density_misfit_after < 0.1 * a.report.density_misfit_before);
    const double log_c = max_abs_log_area(m.vertices, c.sphere, s.triangles);
    const double log_a = max_abs_log_area(m.vertices, a.sphere, s.triangles);
    INFO("max |log area ratio| conformal " << log_c << ", area " << log_a);
    CHECK(log_c > 2.0);            // the squeeze the correction is for
    CHECK(log_a < 0.35 * log_c);   // ... removed to within a small factor
    CHECK(a.report.area_distortion_final < 0.5 * c.report.area_distortion_final);
    const auto b = boundary_vertex_mask(m.num_vertices(), s.triangles);
    for (int i = 0; i < m.num_vertices(); ++i)
      if (b[i]) CHECK(std::abs(a.sphere.row(i).norm() - 1) < 1e-14);
  }
  CHECK(parse_sphere_density("conformal") == InitialMapOptions::SphereDensity::conformal);
  CHECK_THROWS_AS(parse_sphere_density("volume"), InputError);
}

TEST_CASE("initial map of convex and non-convex shapes is fold-free") {
  const auto host = Device::host();
  auto& dev = *host;
  const std::pair<const char*, TetMesh> shapes[] = {
      {"cube", test::cube_mesh(6)},        {"ball", test::ball_mesh(8)},
      {"ellipsoid", test::ellipsoid_mesh(8)}, {"bent", test::bent_mesh(4)},
      {"dumbbell", test::dumbbell_mesh(4)}};
  for (const auto& [name, in] : shapes) {
    INFO(name);
    const InitialMapResult r = initial_map(dev, in);
    check_map(r, in);
  }
}

TEST_CASE("harmonic folds are untangled, without untangling the map is refused") {
  const auto host = Device::host();
  auto& dev = *host;
  const TetMesh in = test::ellipsoid_mesh(8);  // slivers near the rim: the harmonic map folds
  InitialMapOptions opt;
  const InitialMapResult r = initial_map(dev, in, opt);
  CHECK(r.report.folds_before_untangle > 0);
  check_map(r, in);

  opt.untangle = InitialMapOptions::Untangle::Never;
  try {
    initial_map(dev, in, opt);
    FAIL("a folded map was returned");
  } catch (const NumericalError& e) {
    const std::string what = e.what();
    CHECK(what.find("folded") != std::string::npos);
    CHECK(what.find("smallest dihedral angle") != std::string::npos);
  }
  opt.throw_on_folds = false;
  const InitialMapResult folded = initial_map(dev, in, opt);
  CHECK(folded.report.folds_after_untangle > 0);
  CHECK(!inverted_tets(folded.ball, folded.mesh.tets).empty());
}

TEST_CASE("global untangling (Always) keeps the map fold-free") {
  const auto host = Device::host();
  auto& dev = *host;
  const TetMesh in = test::ball_mesh(6);
  InitialMapOptions opt;
  opt.untangle = InitialMapOptions::Untangle::Always;
  const InitialMapResult r = initial_map(dev, in, opt);
  check_map(r, in);
  REQUIRE(r.report.untangle);
  CHECK(!r.report.untangle->local);
  CHECK(to_json(r.report).find("untangle")->find("scope")->string() == "global");
}

TEST_CASE("area correction on the sphere lowers the boundary area distortion") {
  const auto host = Device::host();
  auto& dev = *host;
  const TetMesh in = test::dumbbell_mesh(3);
  InitialMapOptions opt;
  opt.area_correction = true;
  const InitialMapResult r = initial_map(dev, in, opt);
  check_map(r, in);
  const SphereMapReport& b = r.report.boundary;
  REQUIRE(b.area_correction_steps);
  CHECK(*b.area_correction_steps > 0);
  CHECK(b.area_distortion_final < 0.5 * b.area_distortion_conformal);
  CHECK(to_json(r.report).find("boundary")->find("area_correction_steps")->number() == *b.area_correction_steps);
}

TEST_CASE("an input with an inverted tet or a non-ball boundary is refused") {
  const auto host = Device::host();
  auto& dev = *host;
  TetMesh in = test::cube_mesh(2);
  std::swap(in.tets(3, 0), in.tets(3, 1));
  CHECK_THROWS_AS(initial_map(dev, in), InputError);
  // two separate cubes: the boundary has two components
  TetMesh a = test::cube_mesh(1), two;
  two.vertices.resize(2 * a.num_vertices(), 3);
  two.vertices << a.vertices, (a.vertices.array() + 3.0).matrix();
  two.tets.resize(2 * a.num_tets(), 4);
  two.tets << a.tets, (a.tets.array() + a.num_vertices()).matrix();
  CHECK_THROWS_AS(initial_map(dev, two), InputError);
}

TEST_CASE("host and OpenCL device give the same initial map") {
  const TetMesh in = test::bent_mesh(4);
  Points ref;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    const InitialMapResult r = initial_map(*dev, in);
    check_map(r, in);
    if (ref.rows() == 0) {
      ref = r.ball;
      continue;
    }
    REQUIRE(r.ball.rows() == ref.rows());
    CHECK((r.ball - ref).cwiseAbs().maxCoeff() < 1e-6);  // CG to 1e-10 relative residual on both
  }
}

namespace {
// A rod of aspect `aspect` (nx x 2 x 2 cells): its conformal sphere map shrinks the far end by
// about e^(-aspect), below double precision from aspect ~ 35.
TetMesh rod_mesh(int nx, double aspect) {
  TetMesh m = test::box_mesh(nx, 2, 2);
  m.vertices.col(0) *= aspect * 2.0 / nx;
  return m;
}
// The sphere map of test::ellipsoid_mesh(8)'s boundary forced to start from `start` (named
// `name`): flip-free from it, and the area flow equalises from it.
void check_forced_start_on_ellipsoid(InitialMapOptions::SphereStart start, const char* name) {
  const TetMesh e = test::ellipsoid_mesh(8);
  InitialMapOptions o;
  o.sphere_start = start;
  const SphereMapResult b = sphere_map(TriSurface{e.vertices, boundary_faces(e.tets)}, o);
  CHECK(b.flipped_triangles == 0);
  CHECK(b.report.start == name);
  CHECK(b.report.density_kept);
  CHECK(b.report.area_distortion_final < 0.1);
  CHECK(parse_sphere_start(name) == start);
}
int inward_faces(const Points& s, const Triangles& f) {
  int bad = 0;
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const Eigen::Vector3d a = s.row(f(t, 0)), b = s.row(f(t, 1)), c = s.row(f(t, 2));
    bad += !(a.dot(b.cross(c)) > 0);
  }
  return bad;
}
}  // namespace

TEST_CASE("progressive sphere embedding: flip-free on any closed genus-0 surface, refuses a torus") {
  for (const auto& [name, m] : {std::pair<const char*, TetMesh>{"ellipsoid", test::ellipsoid_mesh(6)},
                                {"rod 60", rod_mesh(120, 60)}, {"bent", test::bent_mesh(3)}}) {
    INFO(name);
    TriSurface s{m.vertices, boundary_faces(m.tets)};
    // compact the surface: only boundary vertices
    std::vector<int> id(static_cast<size_t>(m.num_vertices()), -1);
    std::vector<int> used;
    for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
      for (int c = 0; c < 3; ++c)
        if (id[static_cast<size_t>(s.triangles(t, c))] < 0) {
          id[static_cast<size_t>(s.triangles(t, c))] = static_cast<int>(used.size());
          used.push_back(s.triangles(t, c));
        }
    Points in(static_cast<Eigen::Index>(used.size()), 3);
    for (size_t i = 0; i < used.size(); ++i) in.row(static_cast<Eigen::Index>(i)) = m.vertices.row(used[i]);
    Triangles f = s.triangles;
    for (Eigen::Index t = 0; t < f.rows(); ++t)
      for (int c = 0; c < 3; ++c) f(t, c) = id[static_cast<size_t>(f(t, c))];
    detail::ProgressiveStats st;
    const Points p = detail::progressive_sphere(in, f, &st);
    REQUIRE(p.rows() == in.rows());
    CHECK(st.collapses == in.rows() - 4);
    CHECK(st.passes > 0);
    CHECK((p.rowwise().norm().array() - 1).abs().maxCoeff() < 1e-14);
    CHECK(inward_faces(p, f) == 0);
    // a bijection onto the sphere: the chord triangles' solid angles add up to 4 pi
    double solid = 0;
    for (Eigen::Index t = 0; t < f.rows(); ++t) {
      const Eigen::Vector3d a = p.row(f(t, 0)), b = p.row(f(t, 1)), c = p.row(f(t, 2));
      solid += 2 * std::atan2(a.dot(b.cross(c)), 1 + a.dot(b) + b.dot(c) + c.dot(a));
    }
    CHECK(std::abs(solid - 4 * M_PI) < 1e-9);
  }
  const TetMesh torus = test::tunnel_cube();
  const Triangles tf = boundary_faces(torus.tets);
  CHECK_THROWS_AS(detail::progressive_sphere(torus.vertices, tf), InputError);
}

TEST_CASE("sphere map: where the conformal map flips triangles the progressive start takes over") {
  // bent_mesh(3): 128 boundary vertices on a 270-degree C; the conformal scale factors reach
  // 1e-11 and chord triangles face inwards on the sphere
  const TetMesh m = test::bent_mesh(3);
  const TriSurface s{m.vertices, boundary_faces(m.tets)};
  const SphereMapResult a = sphere_map(s);
  CHECK(a.report.flipped_after_conformal > 0);
  CHECK(a.report.start == "progressive");
  CHECK(a.flipped_triangles == 0);
  CHECK(a.report.progressive_passes);
  CHECK(a.report.area_distortion_final < a.report.area_distortion_conformal);
  const Json j = to_json(a.report);
  REQUIRE(j.find("progressive"));
  CHECK(j.find("start")->string() == "progressive");
  CHECK(j.find("progressive")->find("collapses")->number() > 0);
  // the whole initial map from it is a valid map
  const auto host = Device::host();
  const InitialMapResult r = initial_map(*host, m);
  check_map(r, m);
  CHECK(r.report.boundary.start == "progressive");
  // forced on a brain-like shape it is flip-free too, and the area flow equalises from it
  check_forced_start_on_ellipsoid(InitialMapOptions::SphereStart::progressive, "progressive");
  CHECK_THROWS_AS(parse_sphere_start("tutte"), InputError);
}

TEST_CASE("sphere map: where the conformal start stays crowded after the area flow the progressive start is tried and kept when better") {
  // a ball with six limbs (radius 1 + 4 exp(-(angle / 0.4)^2) towards each axis): its conformal
  // map does not flip but crushes the limbs' ends, and the area flow does not recover them
  TetMesh m = test::smooth_ball_mesh(10);
  const Eigen::Vector3d axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (Eigen::Index i = 0; i < m.vertices.rows(); ++i) {
    const Eigen::Vector3d x = m.vertices.row(i);
    if (!(x.norm() > 0)) continue;
    double g = 1;
    for (const auto& d : axes) {
      const double angle = std::acos(std::clamp(x.dot(d) / x.norm(), -1.0, 1.0)) / 0.4;
      g += 4 * std::exp(-angle * angle);
    }
    m.vertices.row(i) *= g;
  }
  const SphereMapResult a = sphere_map(TriSurface{m.vertices, boundary_faces(m.tets)});
  CHECK(a.report.flipped_after_conformal == 0);
  REQUIRE(a.report.conformal_log_misfit);
  REQUIRE(a.report.progressive_log_misfit);
  CHECK(*a.report.conformal_log_misfit > SphereMapReport::kCrowdedMisfit);
  CHECK(*a.report.progressive_log_misfit < 0.01 * *a.report.conformal_log_misfit);
  CHECK(a.report.start == "progressive");
  CHECK(a.report.density_misfit_after == *a.report.progressive_log_misfit);
  CHECK(a.flipped_triangles == 0);
  CHECK(a.report.area_distortion_final < 0.25);
  const Json j = to_json(a.report);
  CHECK(j.find("conformal_log_misfit")->number() == *a.report.conformal_log_misfit);
  CHECK(j.find("progressive_log_misfit")->number() == *a.report.progressive_log_misfit);
  // a shape the conformal start serves is not compared
  const TetMesh e = test::ellipsoid_mesh(8);
  const SphereMapResult b = sphere_map(TriSurface{e.vertices, boundary_faces(e.tets)});
  CHECK(b.report.start == "conformal");
  CHECK(!b.report.conformal_log_misfit);
  CHECK(!to_json(b.report).find("conformal_log_misfit"));
}

TEST_CASE("axial sphere map: a coiled tube goes from pole to pole with each band's area, and wins the automatic start") {
  // 2.25 turns of a tube of radius 0.27 (the coil of bench/shapes): about 50 radii long; its
  // conformal map flips, and the progressive embedding leaves the ends crushed
  const int n = 160, m = 24;
  const TriSurface s = helix_tube(2.25, 0.27, n, m);
  detail::AxialStats st;
  const Points p = detail::axial_sphere(s.vertices, s.triangles, &st);
  REQUIRE(p.rows() == s.vertices.rows());
  CHECK(inward_faces(p, s.triangles) == 0);
  CHECK((p.rowwise().norm().array() - 1).abs().maxCoeff() < 1e-14);
  // the poles are the two ends (a cap's vertex or its ring's)
  const auto ring_of = [&](int i) { return i >= n * m ? (i == n * m ? 0 : n - 1) : i / m; };
  CHECK(std::min(ring_of(st.north), ring_of(st.south)) == 0);
  CHECK(std::max(ring_of(st.north), ring_of(st.south)) == n - 1);
  CHECK(std::abs(p(st.north, 2) - 1) < 1e-15);
  CHECK(std::abs(p(st.south, 2) + 1) < 1e-15);
  // away from the ends ring i lies around the axis, the cap it bounds with the share of the
  // area up to ring i (Archimedes: a cap's area is 2 pi (1 - z))
  const Eigen::VectorXd share = detail::vertex_area_shares(s.vertices, s.triangles);
  const bool first_north = ring_of(st.north) == 0;
  double below = share(first_north ? n * m : n * m + 1), worst = 0, spread = 0;
  for (int k = 0; k < n; ++k) {
    const int i = first_north ? k : n - 1 - k;
    double z = 0, zmin = 1, zmax = -1, ring = 0;
    for (int j = 0; j < m; ++j) {
      const double zj = p(i * m + j, 2);
      z += zj / m;
      zmin = std::min(zmin, zj);
      zmax = std::max(zmax, zj);
      ring += share(i * m + j);
    }
    if (k >= 4 && k < n - 4) {
      worst = std::max(worst, std::abs(2 * M_PI * (1 - z) / (4 * M_PI) - (below + 0.5 * ring)));
      spread = std::max(spread, zmax - zmin);
    }
    below += ring;
  }
  CHECK(worst < 0.002);
  CHECK(spread < 0.04);
  // the automatic start compares it with the progressive one and keeps it
  const SphereMapResult a = sphere_map(s);
  CHECK(a.report.flipped_after_conformal > 0);
  REQUIRE(a.report.axial_log_misfit);
  REQUIRE(a.report.progressive_log_misfit);
  CHECK(*a.report.axial_log_misfit < 0.1 * *a.report.progressive_log_misfit);
  CHECK(a.report.start == "axial");
  CHECK(a.flipped_triangles == 0);
  CHECK(a.report.area_distortion_final < 0.05);
  const Json j = to_json(a.report);
  CHECK(j.find("start")->string() == "axial");
  CHECK(j.find("axial_log_misfit")->number() == *a.report.axial_log_misfit);
  REQUIRE(j.find("axial"));
  // forced on a brain-like shape it is flip-free too, and the area flow equalises from it
  check_forced_start_on_ellipsoid(InitialMapOptions::SphereStart::axial, "axial");
}

TEST_CASE("initial map of a long rod from the axial start: a valid map, closer than from the progressive start") {
  const TetMesh m = rod_mesh(60, 30);
  const auto host = Device::host();
  InitialMapOptions ax, prog;
  ax.sphere_start = InitialMapOptions::SphereStart::axial;
  prog.sphere_start = InitialMapOptions::SphereStart::progressive;
  const InitialMapResult a = initial_map(*host, m, ax);
  check_map(a, m);
  CHECK(a.report.boundary.start == "axial");
  const InitialMapResult p = initial_map(*host, m, prog);
  check_map(p, m);
  CHECK(p.report.boundary.start == "progressive");
  // on this rod 0.51 against 0.97, and 0.32-0.45 against 0.62: 0.45 where the local untangling
  // clears the axial map's 20 folds (an Intel Xeon), 0.32 where it leaves some and the redo maps
  // the axial start without the area flow (an AMD EPYC; the untangler's rounding differs)
  CHECK(a.report.boundary.area_distortion_final < 0.7 * p.report.boundary.area_distortion_final);
  CHECK(a.report.metrics.vertex_volume_ratio.mean_abs_dev < 0.8 * p.report.metrics.vertex_volume_ratio.mean_abs_dev);
}

TEST_CASE("initial map from an automatic axial start: folds its local runs leave are untangled globally, with no conformal redo") {
  // the automatic start picks the axial map for a thin coiled tube (4 turns, 5,542 tets), and
  // local runs of one L-BFGS step on one ring leave its folds; the conformal redo would crush
  // the tube
  const TetMesh m = tetrahedralize_surface(helix_tube(4, 0.15, 200, 8), TetgenOptions{});
  const auto host = Device::host();
  InitialMapOptions opt;
  opt.local_untangle_rings = 1;
  opt.untangle_options.max_outer_iterations = 1;
  opt.untangle_options.max_lbfgs_iterations = 1;
  const InitialMapResult r = initial_map(*host, m, opt);
  check_map(r, m);
  const InitialMapReport& rep = r.report;
  INFO("folds before " << rep.folds_before_untangle << ", fallback " << rep.fallback.has_value());
  REQUIRE(rep.fallback);
  CHECK(rep.fallback->axial);
  CHECK_FALSE(rep.fallback->crowded);
  CHECK(rep.fallback->folds_after_untangle > 0);
  CHECK(rep.boundary.start == "axial");
  REQUIRE(rep.untangle);
  CHECK_FALSE(rep.untangle->local);  // the global run
  const Json j = to_json(rep);
  const Json* f = j.find("fallback");
  REQUIRE(f);
  CHECK(f->find("to")->string() == "axial");
  CHECK(f->find("axial")->boolean());
}

TEST_CASE("boundary_tet_ratio_bound: exact for one tet, above every fold-free interior's smallest ratio, sees a crushed face") {
  // one regular tet inscribed in the sphere: each face's plane lies 1/3 from the origin, the apex
  // 4/3 from it, so every face's bound is the tet's own ratio, 1
  TetMesh one;
  one.vertices.resize(4, 3);
  one.vertices << 1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1;
  one.vertices /= std::sqrt(3.0);
  one.tets.resize(1, 4);
  one.tets << 0, 1, 2, 3;
  if (tet_volumes(one.vertices, one.tets)(0) < 0) std::swap(one.tets(0, 2), one.tets(0, 3));
  CHECK(boundary_tet_ratio_bound(one, one.vertices) == Approx(1).epsilon(1e-12));

  auto host = Device::host();
  const InitialMapResult im = initial_map(*host, test::ellipsoid_mesh(6));
  const Eigen::VectorXd v0 = tet_volumes(im.mesh.vertices, im.mesh.tets), v1 = tet_volumes(im.ball, im.mesh.tets);
  REQUIRE(v1.minCoeff() > 0);
  const double least = ((v1 / v1.sum()).array() / (v0 / v0.sum()).array()).minCoeff();
  const double bound = boundary_tet_ratio_bound(im.mesh, im.ball);
  INFO("smallest ratio " << least << ", bound " << bound);
  CHECK(least <= bound);
  CHECK(bound < 4);  // of order one where the boundary map keeps its faces' areas
  // a boundary vertex moved along the sphere to within 1e-9 of a neighbour crushes the faces on
  // that edge: no interior can then keep their tets' volumes
  const Triangles faces = boundary_faces(im.mesh.tets);
  Points crushed = im.ball;
  const int a = faces(0, 0), b = faces(0, 1);
  crushed.row(a) = (im.ball.row(b) + 1e-9 * (im.ball.row(a) - im.ball.row(b))).normalized();
  CHECK(boundary_tet_ratio_bound(im.mesh, crushed) < InitialMapReport::kCrowdedRatio);
}
