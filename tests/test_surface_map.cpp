// The area-preserving map of closed surfaces to the sphere (vpm/surface_map.hpp), its input
// checks, FreeSurfer surfaces (host/io/freesurfer.cpp), and `vpm map SURFACE`.
#include <catch2/catch.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include "support/devices.hpp"
#include "support/process.hpp"
#include "support/scratch.hpp"
#include "vpm/config.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/surface_map.hpp"

using namespace vpm;
using vpm::test::run_status;
using vpm::test::slurp;

namespace {

const std::string kVpm = VPM_BINARY;

// An ellipsoid 1.8 : 1 : 0.6 with a bump of 40 % on one side (non-uniform areas that the
// conformal map does not keep), from the icosphere of `level`.
TriSurface bumpy_ellipsoid(int level) {
  TriSurface s = icosphere(level);
  const Eigen::RowVector3d bump(0.6, 0.0, 0.8);
  for (Eigen::Index i = 0; i < s.vertices.rows(); ++i) {
    const Eigen::RowVector3d p = s.vertices.row(i);
    const double g = 1.0 + 0.4 * std::exp(-(p - bump).squaredNorm() / 0.15);
    s.vertices.row(i) = Eigen::RowVector3d(1.8 * p(0), p(1), 0.6 * p(2)) * g;
  }
  return s;
}

// The icosphere of `level` with four spikes (radius 1 + 3 exp(-(angle / 0.2)^2) along each of
// four axes): limbs that the sphere map leaves crushed (face area mean abs(r-1) 14 %).
TriSurface spiky_sphere(int level) {
  TriSurface s = icosphere(level);
  const Eigen::Vector3d axes[] = {{1, 0, 0}, {-1, 0.2, 0}, {0, 1, 0.3}, {0.2, -0.3, 1}};
  for (Eigen::Index i = 0; i < s.vertices.rows(); ++i) {
    const Eigen::Vector3d p = s.vertices.row(i).normalized().transpose();
    double r = 1;
    for (const Eigen::Vector3d& a : axes) {
      const double angle = std::acos(std::clamp(p.dot(a.normalized()), -1.0, 1.0));
      r += 3 * std::exp(-(angle / 0.2) * (angle / 0.2));
    }
    s.vertices.row(i) = r * p.transpose();
  }
  return s;
}

void check_on_sphere_without_flips(const SurfaceMapResult& r, const TriSurface& s) {
  REQUIRE(r.sphere.rows() == s.vertices.rows());
  for (Eigen::Index i = 0; i < r.sphere.rows(); ++i) REQUIRE(std::abs(r.sphere.row(i).norm() - 1.0) < 1e-12);
  const SurfaceMetrics m = surface_metrics(s.vertices, r.sphere, s.triangles);
  CHECK(m.flipped_faces == 0);
  CHECK(r.report.final.flipped_faces == 0);
  CHECK(m.face_area_ratio.mean_abs_dev == Approx(r.report.final.face_area_ratio.mean_abs_dev).epsilon(1e-12));
}

// A disk with a bump (a polar grid of `rings` x `sectors`, no face with three boundary corners).
TriSurface bumpy_disk(int rings, int sectors) {
  TriSurface s;
  s.vertices.resize(1 + rings * sectors, 3);
  s.vertices.row(0) << 0, 0, 0;
  auto idx = [&](int i, int j) { return 1 + (i - 1) * sectors + (j % sectors); };
  for (int i = 1; i <= rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      const double a = 2 * M_PI * (j + 0.5 * (i % 2)) / sectors, r = static_cast<double>(i) / rings;
      const double x = r * std::cos(a), y = r * std::sin(a);
      s.vertices.row(idx(i, j)) << x, y, 0.5 * std::exp(-((x - 0.3) * (x - 0.3) + y * y) / 0.08);
    }
  std::vector<std::array<int, 3>> f;
  for (int j = 0; j < sectors; ++j) f.push_back({0, idx(1, j), idx(1, j + 1)});
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < sectors; ++j) {
      const int a = idx(i, j), b = idx(i, j + 1);
      if (i % 2) {
        f.push_back({a, idx(i + 1, j + 1), b});
        f.push_back({b, idx(i + 1, j + 1), idx(i + 1, j + 2)});
      } else {
        f.push_back({a, idx(i + 1, j), idx(i + 1, j + 1)});
        f.push_back({a, idx(i + 1, j + 1), b});
      }
    }
  s.triangles.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t t = 0; t < f.size(); ++t) s.triangles.row(static_cast<Eigen::Index>(t)) << f[t][0], f[t][1], f[t][2];
  return s;
}

// bumpy_disk cut by a straight line (the faces whose centroid has x < 0.55 kept, vertices
// renumbered): the cut's zigzag leaves faces whose three corners are on the boundary (ears).
TriSurface cut_disk() {
  const TriSurface d = bumpy_disk(12, 48);
  std::vector<int> id(static_cast<size_t>(d.vertices.rows()), -1), kept;
  std::vector<Eigen::RowVector3i> faces;
  for (Eigen::Index t = 0; t < d.triangles.rows(); ++t) {
    const double x = d.vertices(d.triangles(t, 0), 0) + d.vertices(d.triangles(t, 1), 0) + d.vertices(d.triangles(t, 2), 0);
    if (x / 3 >= 0.55) continue;
    Eigen::RowVector3i f;
    for (int k = 0; k < 3; ++k) {
      int& v = id[static_cast<size_t>(d.triangles(t, k))];
      if (v < 0) v = static_cast<int>(kept.size()), kept.push_back(d.triangles(t, k));
      f(k) = v;
    }
    faces.push_back(f);
  }
  TriSurface s;
  s.vertices.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t i = 0; i < kept.size(); ++i) s.vertices.row(static_cast<Eigen::Index>(i)) = d.vertices.row(kept[i]);
  s.triangles.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t t = 0; t < faces.size(); ++t) s.triangles.row(static_cast<Eigen::Index>(t)) = faces[t];
  return s;
}

}  // namespace

TEST_CASE("disk map: a disk with a bump reaches face areas within 0.5 %, boundary on the circle, none flipped") {
  const TriSurface s = bumpy_disk(12, 48);
  REQUIRE(surface_domain(s) == SurfaceDomain::disk);
  validate_disk_surface(s, "disk");
  const SurfaceMapResult r = map_to_disk(s);
  const SurfaceMapReport& rep = r.report;
  CHECK(rep.domain == SurfaceDomain::disk);
  CHECK(rep.boundary_vertices == 48);
  CHECK(rep.ears == 0);
  CHECK(rep.initial.face_area_ratio.mean_abs_dev > 0.05);
  CHECK(rep.final.face_area_ratio.mean_abs_dev <= 0.005);
  CHECK(rep.final.flipped_faces == 0);
  CHECK(rep.final.max_radius_error < 1e-12);
  CHECK(r.sphere.col(2).cwiseAbs().maxCoeff() == 0.0);
  for (Eigen::Index i = 0; i < r.sphere.rows(); ++i) REQUIRE(r.sphere.row(i).norm() <= 1 + 1e-12);
  const SurfaceMetrics m = surface_metrics(s.vertices, r.sphere, s.triangles, SurfaceDomain::disk);
  CHECK(m.face_area_ratio.mean_abs_dev == Approx(rep.final.face_area_ratio.mean_abs_dev).epsilon(1e-12));
  // the same disk mirrored (faces turning the other way) maps as well
  TriSurface mirrored = s;
  mirrored.vertices.col(0) *= -1;
  CHECK(map_to_disk(mirrored).report.final.face_area_ratio.mean_abs_dev <= 0.005);
  // refused: a closed surface
  CHECK_THROWS_WITH(validate_disk_surface(icosphere(2), "s.off"), Catch::Contains("closed"));
  Json j = to_json(rep);
  CHECK(j["domain"].string() == "disk");
  CHECK(j["disk_map"]["boundary_vertices"].number() == 48);
}

TEST_CASE("disk map: ears are split (an interior edge halved each) and then keep their area") {
  const TriSurface s = cut_disk();
  validate_disk_surface(s, "cut disk");
  const Eigen::Index n = s.vertices.rows(), m = s.triangles.rows();
  SurfaceMapOptions keep;
  keep.split_ears = false;
  const SurfaceMapResult as_is = map_to_disk(s, keep);
  CHECK(as_is.report.ears == 4);
  CHECK(as_is.report.split_edges == 0);
  CHECK(as_is.sphere.rows() == n);
  CHECK(&mapped_faces(s.triangles, as_is) == &s.triangles);
  CHECK(as_is.report.final.face_area_ratio.min < 0.05);  // the ears stay crushed on the circle

  const SurfaceMapResult r = map_to_disk(s);
  const SurfaceMapReport& rep = r.report;
  CHECK(rep.ears == 4);
  CHECK(rep.split_edges == 4);
  REQUIRE(r.added.size() == 4);
  REQUIRE(r.sphere.rows() == n + 4);
  const Triangles& f = mapped_faces(s.triangles, r);
  CHECK(f.rows() == m + 8);  // each halved edge splits its two faces
  CHECK(f.maxCoeff() == n + 3);
  CHECK(rep.final.flipped_faces == 0);
  CHECK(rep.final.face_area_ratio.mean_abs_dev <= 0.005);
  CHECK(rep.final.face_area_ratio.min > 0.8);
  CHECK(rep.final.face_ratio.size() == f.rows());
  for (int i = 0; i < 4; ++i) CHECK(r.sphere.row(n + i).norm() < 1 - 1e-6);  // the new vertices are interior
  // the input's positions carried: the added rows the midpoints of their edges; the metrics
  // against them are the report's
  const FieldValues ref = extend_to_mapped(s.vertices, r);
  REQUIRE(ref.rows() == n + 4);
  CHECK(ref.topRows(n) == FieldValues(s.vertices));
  for (int i = 0; i < 4; ++i)
    CHECK((ref.row(n + i) - 0.5 * (s.vertices.row(r.added[i][0]) + s.vertices.row(r.added[i][1]))).norm() == 0.0);
  const SurfaceMetrics again = surface_metrics(ref, r.sphere, f, SurfaceDomain::disk);
  CHECK(again.face_area_ratio.mean_abs_dev == Approx(rep.final.face_area_ratio.mean_abs_dev).epsilon(1e-12));
  CHECK_THROWS_WITH(extend_to_mapped(FieldValues::Zero(n + 1, 1), r), Catch::Contains("rows"));
  CHECK(to_json(rep)["disk_map"]["split_edges"].number() == 4);
  // vpm map writes the split surface: its vertices and faces, the input positions there
  const std::string dir = vpm::test::fresh_dir("ears");
  write_surface(dir + "/cut.off", s);
  REQUIRE(run_status(kVpm + " map " + dir + "/cut.off -o " + dir + "/disk.vtp --report " + dir + "/r.json --quiet") ==
          0);
  const TriSurface out = read_surface(dir + "/disk.vtp");
  CHECK(out.vertices.rows() == n + 4);
  CHECK(out.triangles == f);
  CHECK_THAT(slurp(dir + "/disk.vtp"), Catch::Contains("Name=\"original_position\""));
  Json j = Json::parse(slurp(dir + "/r.json"));
  CHECK(j["disk_map"]["split_edges"].number() == 4);
  CHECK(j["input"]["vertices"].number() == static_cast<double>(n));
}

TEST_CASE("surface map: an ellipsoid with a bump reaches face areas within 0.5 %, every face outwards") {
  const TriSurface s = bumpy_ellipsoid(4);
  const SurfaceMapResult r = map_to_sphere(s);
  check_on_sphere_without_flips(r, s);
  const SurfaceMapReport& rep = r.report;
  INFO("sphere map " << rep.initial.face_area_ratio.mean_abs_dev << " final " << rep.final.face_area_ratio.mean_abs_dev);
  // the polish does the work the sphere map leaves
  CHECK(rep.initial.face_area_ratio.mean_abs_dev > 0.01);
  CHECK(rep.final.face_area_ratio.mean_abs_dev <= 0.005);
  CHECK(rep.converged);
  CHECK(rep.stop_reason == "tolerance");
  CHECK(!rep.polish.empty());
  CHECK(rep.final.vertex_area_ratio.mean_abs_dev < rep.initial.vertex_area_ratio.mean_abs_dev);
  // without the polish the map is the sphere map's
  SurfaceMapOptions none;
  none.polish_rounds = 0;
  const SurfaceMapResult r0 = map_to_sphere(s, none);
  CHECK(r0.report.stop_reason == "none");
  CHECK(r0.report.final.face_area_ratio.mean_abs_dev == Approx(rep.initial.face_area_ratio.mean_abs_dev).epsilon(1e-9));
  // a tighter tolerance is reached by more steps
  SurfaceMapOptions tight;
  tight.tolerance = 0.002;
  const SurfaceMapResult r2 = map_to_sphere(s, tight);
  CHECK(r2.report.final.face_area_ratio.mean_abs_dev <= 0.002);
  CHECK(r2.report.polish.size() > rep.polish.size());
  // the report's keys (docs/surfaces.md)
  Json j = to_json(rep);
  for (const char* k : {"input", "initial", "final", "rounds", "sphere_map", "stop_reason", "converged", "convergence", "timings_s"})
    CHECK(j.find(k) != nullptr);
  CHECK(j["final"]["face_area_ratio"]["mean_abs_dev"].number() <= 0.005);
  CHECK(j["rounds"].at(0).find("kind")->string() == "polish");
}

TEST_CASE("surface map: limbs crushed by the sphere map get their area back (steps solved again around faces that would flip)") {
  const TriSurface s = spiky_sphere(3);
  const SurfaceMapResult r = map_to_sphere(s);
  check_on_sphere_without_flips(r, s);
  const SurfaceMapReport& rep = r.report;
  INFO("sphere map " << rep.initial.face_area_ratio.mean_abs_dev << " final " << rep.final.face_area_ratio.mean_abs_dev
                     << " after " << rep.polish.size() << " steps (" << rep.stop_reason << ")");
  CHECK(rep.initial.face_area_ratio.mean_abs_dev > 0.1);
  // zeroing the held vertices' rows of a step solved with them free stalled at 4 %
  CHECK(rep.final.face_area_ratio.mean_abs_dev < 0.02);
  size_t held = 0;
  for (const SurfaceMapStep& st : rep.polish) held += st.frozen_vertices > 0;
  CHECK(held > 0);  // the case the test is about: steps that would flip faces
}

TEST_CASE("surface map on host and device: the equal-area steps' solves on PoCL give the host's map") {
  const TriSurface s = bumpy_ellipsoid(3);
  SurfaceMapOptions o, sphere_only;
  o.sphere.density_solve = InitialMapOptions::DensitySolve::device;  // the device even for a small surface
  sphere_only = o;
  sphere_only.polish_rounds = 0;
  Points host_sphere;
  SurfaceMapReport host;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    const SurfaceMapResult r0 = map_to_sphere(s, sphere_only, dev.get()), r = map_to_sphere(s, o, dev.get());
    check_on_sphere_without_flips(r, s);
    CHECK(r.report.final.face_area_ratio.mean_abs_dev <= 0.005);
    if (dev->is_host()) {
      host_sphere = r0.sphere, host = r.report;
      CHECK(r.report.sphere.density_solver != "device-amg-cg");
      continue;
    }
    CHECK(r.report.sphere.density_solver == "device-amg-cg");
    // AMG-CG to a relative residual of 1e-10 against the host's Cholesky: the same sphere map; the
    // polish from it takes the same steps to the same distortion (its CGLS stops on residuals, so
    // the points agree to the tolerance's scale, not to round-off)
    CHECK((r0.sphere - host_sphere).cwiseAbs().maxCoeff() < 1e-6);
    CHECK(r.report.polish.size() == host.polish.size());
    CHECK(r.report.final.face_area_ratio.mean_abs_dev == Approx(host.final.face_area_ratio.mean_abs_dev).epsilon(0.02));
  }
}

TEST_CASE("surface map: a surface with inward faces is mapped with them reversed, as well") {
  TriSurface s = bumpy_ellipsoid(3);
  s.triangles.col(1).swap(s.triangles.col(2));
  const SurfaceMapResult r = map_to_sphere(s);
  CHECK(r.report.reversed);
  CHECK(r.report.final.face_area_ratio.mean_abs_dev <= 0.005);
  CHECK(r.report.final.flipped_faces == 0);  // counted with the faces turned outwards
}

TEST_CASE("surface map: surfaces that are not one closed genus-0 surface are refused with the reason") {
  const TriSurface ok = icosphere(2);
  auto refused = [](const TriSurface& s, const std::string& words) {
    INFO(words);
    try {
      validate_closed_surface(s, "in.off");
      FAIL("accepted");
    } catch (const InputError& e) {
      CHECK_THAT(e.what(), Catch::StartsWith("in.off: ") && Catch::Contains(words));
    }
    CHECK_THROWS_AS(map_to_sphere(s), InputError);
  };
  validate_closed_surface(ok, "in.off");
  TriSurface hole = ok;
  hole.triangles.conservativeResize(ok.triangles.rows() - 1, 3);
  refused(hole, "holes");
  TriSurface two = ok;
  two.vertices.conservativeResize(2 * ok.vertices.rows(), 3);
  two.vertices.bottomRows(ok.vertices.rows()) = ok.vertices.array() + 3.0;
  two.triangles.conservativeResize(2 * ok.triangles.rows(), 3);
  two.triangles.bottomRows(ok.triangles.rows()) = ok.triangles.array() + static_cast<int>(ok.vertices.rows());
  refused(two, "2 separate surfaces");
  TriSurface flipped = ok;
  std::swap(flipped.triangles(0, 1), flipped.triangles(0, 2));
  refused(flipped, "not consistently oriented");
  TriSurface unused = ok;
  unused.vertices.conservativeResize(ok.vertices.rows() + 1, 3);
  unused.vertices.bottomRows(1) << 5, 5, 5;
  refused(unused, "in no triangle");
  TriSurface flat = ok;  // a face with no area: two corners at one point
  flat.vertices.row(flat.triangles(0, 1)) = flat.vertices.row(flat.triangles(0, 0));
  refused(flat, "no area");
  TriSurface bad_index = ok;
  bad_index.triangles(3, 2) = 100000;
  refused(bad_index, "out of range");
  // a torus (genus 1): 8 x 6 quads
  TriSurface torus;
  const int nu = 8, nv = 6;
  torus.vertices.resize(nu * nv, 3);
  torus.triangles.resize(2 * nu * nv, 3);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      torus.vertices.row(i * nv + j) << (2 + std::cos(v)) * std::cos(u), (2 + std::cos(v)) * std::sin(u), std::sin(v);
      const int a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv, d = i * nv + (j + 1) % nv;
      torus.triangles.row(2 * a) << a, b, c;
      torus.triangles.row(2 * a + 1) << a, c, d;
    }
  refused(torus, "genus 1");
}

TEST_CASE("FreeSurfer surfaces: written and read back exactly at float precision, corrupt files name the byte") {
  const std::string dir = vpm::test::fresh_dir("freesurfer");
  TriSurface s = bumpy_ellipsoid(2);
  for (Eigen::Index i = 0; i < s.vertices.rows(); ++i)
    for (int k = 0; k < 3; ++k) s.vertices(i, k) = static_cast<float>(s.vertices(i, k));
  write_surface(dir + "/lh.white", s);
  REQUIRE(is_surface_path(dir + "/lh.white"));
  const TriSurface back = read_surface(dir + "/lh.white");
  CHECK(back.vertices == s.vertices);
  CHECK(back.triangles == s.triangles);
  // recognised by its first bytes whatever its name
  std::filesystem::copy_file(dir + "/lh.white", dir + "/subject_surface");
  CHECK(is_surface_path(dir + "/subject_surface"));
  CHECK(read_surface(dir + "/subject_surface").triangles == s.triangles);

  const std::string bytes = slurp(dir + "/lh.white");
  auto corrupt = [&](std::string data, const std::string& words) {
    INFO(words);
    const std::string p = dir + "/bad.pial";
    std::ofstream(p, std::ios::binary).write(data.data(), static_cast<std::streamsize>(data.size()));
    try {
      read_surface(p);
      FAIL("read");
    } catch (const InputError& e) {
      CHECK_THAT(e.what(), Catch::StartsWith(p + ":byte ") && Catch::Contains(words));
    }
  };
  const size_t counts = bytes.find("\n\n") + 2;
  corrupt(bytes.substr(0, bytes.size() - 5), "truncated");
  std::string quad = bytes;
  quad[2] = static_cast<char>(0xFF);
  corrupt(quad, "quadrangle");
  std::string huge = bytes;
  huge[counts] = 0x7F;  // 2 billion vertices
  corrupt(huge, "vertex count");
  std::string index = bytes;
  index[bytes.size() - 4] = 0x7F;  // the last face's last index, high byte
  corrupt(index, "out of range");
  std::string nan = bytes;
  nan[counts + 8] = 0x7F;
  nan[counts + 9] = static_cast<char>(0xC0);  // the first coordinate a NaN
  corrupt(nan, "not a finite number");
  corrupt(bytes.substr(0, 3) + std::string(5000, 'x'), "two newlines");
}

TEST_CASE("vpm map SURFACE: to the sphere as .vtp with fields, or FreeSurfer, tet-only options and bad surfaces exit 2") {
  const std::string dir = vpm::test::fresh_dir("map_surface");
  write_surface(dir + "/in.off", bumpy_ellipsoid(3));
  REQUIRE(run_status(kVpm + " map " + dir + "/in.off -o " + dir + "/out.vtp --report " + dir + "/r.json --quiet") == 0);
  Json r = Json::parse(slurp(dir + "/r.json"));
  CHECK(r["converged"].boolean());
  CHECK(r["final"]["flipped_faces"].number() == 0);
  CHECK(r["final"]["face_area_ratio"]["mean_abs_dev"].number() <= 0.005);
  CHECK(r.find("device") != nullptr);
  const std::string vtp = slurp(dir + "/out.vtp");
  for (const char* name : {"type=\"PolyData\"", "Name=\"original_position\" NumberOfComponents=\"3\"",
                           "Name=\"vertex_area_ratio\"", "Name=\"face_area_ratio\"", "<Polys>"})
    CHECK_THAT(vtp, Catch::Contains(name));
  // FreeSurfer out, and in again
  REQUIRE(run_status(kVpm + " map " + dir + "/in.off -o " + dir + "/lh.sphere --quiet") == 0);
  const TriSurface sphere = read_surface(dir + "/lh.sphere");
  for (Eigen::Index i = 0; i < sphere.vertices.rows(); ++i) REQUIRE(std::abs(sphere.vertices.row(i).norm() - 1.0) < 1e-6);
  REQUIRE(run_status(kVpm + " map " + dir + "/lh.sphere -o " + dir + "/again.off --quiet") == 0);
  // usage
  CHECK(run_status(kVpm + " map " + dir + "/in.off -o " + dir + "/out.vtp --boundary fixed 2>" + dir + "/e1") == 2);
  CHECK_THAT(slurp(dir + "/e1"), Catch::Contains("tet meshes only"));
  CHECK(run_status(kVpm + " map " + dir + "/in.off -o " + dir + "/out.vtu 2>" + dir + "/e2") == 2);
  CHECK_THAT(slurp(dir + "/e2"), Catch::Contains("output extension"));
  // one hole: a disk, mapped to the unit disk; two holes: refused
  TriSurface hole = icosphere(3);
  hole.triangles.conservativeResize(hole.triangles.rows() - 1, 3);
  write_surface(dir + "/hole.off", hole);
  REQUIRE(run_status(kVpm + " map " + dir + "/hole.off -o " + dir + "/h.vtp --report " + dir + "/h.json --quiet 2>/dev/null") != 2);
  Json h = Json::parse(slurp(dir + "/h.json"));
  CHECK(h["domain"].string() == "disk");
  CHECK(h["final"]["flipped_faces"].number() == 0);
  const TriSurface ico = icosphere(2);
  auto touches = [&](int t) {  // face t shares a vertex with one of face 0's neighbours' vertices
    for (int u = 0; u < ico.triangles.rows(); ++u) {
      bool near0 = false;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) near0 = near0 || ico.triangles(0, a) == ico.triangles(u, b);
      if (!near0) continue;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          if (ico.triangles(u, a) == ico.triangles(t, b)) return true;
    }
    return false;
  };
  int far = 1;
  while (touches(far)) ++far;
  TriSurface holes;
  holes.vertices = ico.vertices;
  holes.triangles.resize(ico.triangles.rows() - 2, 3);
  for (int t = 0, k = 0; t < ico.triangles.rows(); ++t)
    if (t != 0 && t != far) holes.triangles.row(k++) = ico.triangles.row(t);
  write_surface(dir + "/holes.off", holes);
  CHECK(run_status(kVpm + " map " + dir + "/holes.off -o " + dir + "/hh.vtp 2>" + dir + "/e3") == 2);
  CHECK_THAT(slurp(dir + "/e3"), Catch::Contains(dir + "/holes.off: ") && Catch::Contains("more than one boundary loop"));
  CHECK(!std::filesystem::exists(dir + "/hh.vtp"));
  // a surface that misses the tolerance by over 2x: written, exit 4 (--allow-partial 0)
  CHECK(run_status(kVpm + " map " + dir + "/in.off -o " + dir + "/p.vtp --rounds 0 --quiet 2>/dev/null") == 4);
  CHECK(std::filesystem::exists(dir + "/p.vtp"));
  CHECK(run_status(kVpm + " map " + dir + "/in.off -o " + dir + "/p.vtp --rounds 0 --allow-partial --quiet 2>/dev/null") == 0);
}

TEST_CASE("GIfTI surfaces: written and read back at float precision, bad files exit with one line") {
  if (!VPM_HAVE_GIFTI) {
    CHECK_THROWS_WITH(read_surface("x.gii"), Catch::Contains("without expat"));
    return;
  }
  const std::string dir = vpm::test::fresh_dir("gifti");
  TriSurface s = bumpy_ellipsoid(2);
  for (Eigen::Index i = 0; i < s.vertices.rows(); ++i)
    for (int k = 0; k < 3; ++k) s.vertices(i, k) = static_cast<float>(s.vertices(i, k));
  write_surface(dir + "/lh.white.surf.gii", s);
  const TriSurface back = read_surface(dir + "/lh.white.surf.gii");
  CHECK(back.vertices == s.vertices);
  CHECK(back.triangles == s.triangles);
  // no file is left under another name
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  CHECK(files == 1);
  auto refused = [&](const std::string& name, const std::string& text, const std::string& words) {
    INFO(words);
    std::ofstream(dir + "/" + name) << text;
    const int status = run_status(kVpm + " convert " + dir + "/" + name + " " + dir + "/out.off 2>" + dir + "/err.txt");
    CHECK(status == 2);
    const std::string err = slurp(dir + "/err.txt");
    CHECK_THAT(err, Catch::Contains(dir + "/" + name + ": ") && Catch::Contains(words));
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
  };
  refused("garbage.gii", "not xml at all", "not a GIfTI file (line 1: syntax error)");
  const std::string head = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<GIFTI Version=\"1.0\" NumberOfDataArrays=\"1\">";
  // only the GIfTI DTD's element tree is read
  refused("root.gii", "<?xml version=\"1.0\"?>\n<GIFVI><DataArray><Data>1</Data></DataArray></GIFVI>",
          "not a GIfTI file (line 2: element <GIFVI> is not a GIfTI root (<GIFTI>))");
  refused("stray.gii", head + "\n<Data>1 2 3</Data></GIFTI>", "line 3: element <Data> may not appear in <GIFTI>");
  const std::string points =
      "<DataArray Intent=\"NIFTI_INTENT_POINTSET\" DataType=\"NIFTI_TYPE_FLOAT32\" ArrayIndexingOrder=\"RowMajorOrder\" "
      "Dimensionality=\"2\" Dim0=\"3\" Dim1=\"3\" Encoding=\"ASCII\" Endian=\"LittleEndian\" ExternalFileName=\"\" "
      "ExternalFileOffset=\"0\"><Data>0 0 0 1 0 0 0 1 0</Data></DataArray>";
  refused("values.func.gii", head + points + "</GIFTI>", "no DataArray of intent NIFTI_INTENT_TRIANGLE");
  std::string external = points;
  external.replace(external.find("Encoding=\"ASCII\""), 16, "Encoding=\"ExternalFileBinary\"");
  external.replace(external.find("ExternalFileName=\"\""), 19, "ExternalFileName=\"/etc/passwd\"");
  const std::string tri =
      "<DataArray Intent=\"NIFTI_INTENT_TRIANGLE\" DataType=\"NIFTI_TYPE_INT32\" ArrayIndexingOrder=\"RowMajorOrder\" "
      "Dimensionality=\"2\" Dim0=\"1\" Dim1=\"3\" Encoding=\"ASCII\" Endian=\"LittleEndian\" ExternalFileName=\"\" "
      "ExternalFileOffset=\"0\"><Data>0 1 2</Data></DataArray>";
  std::string two = head;
  two.replace(two.find("NumberOfDataArrays=\"1\""), 22, "NumberOfDataArrays=\"2\"");
  refused("external.gii", two + external + tri + "</GIFTI>", "external file");
  std::string huge = tri;
  huge.replace(huge.find("Dim0=\"1\""), 8, "Dim0=\"2000000000\"");
  refused("huge.gii", two + points + huge + "</GIFTI>", "more than vpm reads");
  // big-endian base64 float32 points (GIfTI's Endian attribute) read as the numbers they hold
  std::string big = points;
  big.replace(big.find("Encoding=\"ASCII\""), 16, "Encoding=\"Base64Binary\"");
  big.replace(big.find("LittleEndian"), 12, "BigEndian");
  big.replace(big.find("0 0 0 1 0 0 0 1 0"), 17, "AAAAAAAAAAAAAAAAP4AAAAAAAAAAAAAAAAAAAD/AAAAAAAAA");
  std::ofstream(dir + "/big.gii") << two + big + tri + "</GIFTI>";
  const TriSurface b = read_surface(dir + "/big.gii");
  CHECK(b.vertices(1, 0) == 1.0);
  CHECK(b.vertices(2, 1) == 1.5);
  CHECK(b.vertices.cwiseAbs().sum() == 2.5);
  std::string short_data = big;
  short_data.replace(short_data.find("AAAAAAAA"), 8, "");
  refused("short.gii", two + short_data + tri + "</GIFTI>", "30 bytes of data; its dimensions give 36");
  std::string index = tri;
  index.replace(index.find("0 1 2"), 5, "0 1 7");
  refused("index.gii", two + points + index + "</GIFTI>", "vertex index 7 out of range");
}

TEST_CASE("overlays: FreeSurfer per-vertex files read, carried by vpm map SURFACE --overlays to point fields") {
  const std::string dir = vpm::test::fresh_dir("overlays");
  const TriSurface s = bumpy_ellipsoid(2);
  const long long n = s.vertices.rows();
  std::string bytes("\xFF\xFF\xFF", 3);
  auto be32 = [&bytes](std::uint32_t v) { for (int k = 24; k >= 0; k -= 8) bytes.push_back(static_cast<char>(v >> k)); };
  be32(static_cast<std::uint32_t>(n));
  be32(static_cast<std::uint32_t>(s.triangles.rows()));
  be32(1);
  for (long long i = 0; i < n; ++i) {
    const float x = static_cast<float>(i) / 8.0f;
    std::uint32_t u;
    std::memcpy(&u, &x, 4);
    be32(u);
  }
  std::ofstream(dir + "/lh.curv", std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  const Eigen::VectorXd v = read_overlay(dir + "/lh.curv");
  REQUIRE(v.size() == n);
  for (long long i = 0; i < n; ++i) REQUIRE(v(i) == static_cast<double>(static_cast<float>(i) / 8.0f));
  std::ofstream(dir + "/short.curv", std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size() - 4));
  CHECK_THROWS_WITH(read_overlay(dir + "/short.curv"), Catch::Contains(":byte ") && Catch::Contains("truncated"));
  write_surface(dir + "/lh.white", s);
  REQUIRE(run_status(kVpm + " map " + dir + "/lh.white -o " + dir + "/out.vtp --overlays " + dir + "/lh.curv --quiet") == 0);
  const std::string vtp = slurp(dir + "/out.vtp");
  CHECK_THAT(vtp, Catch::Contains("Name=\"curv\""));
  CHECK_THAT(vtp, Catch::Contains("\n0.125\n"));  // vertex 1's value, in the field's rows
  // another surface's file, and a tet mesh: exit 2
  write_surface(dir + "/other.off", icosphere(1));
  CHECK(run_status(kVpm + " map " + dir + "/other.off -o " + dir + "/o.vtp --overlays " + dir + "/lh.curv 2>" + dir + "/e") == 2);
  CHECK_THAT(slurp(dir + "/e"), Catch::Contains(dir + "/lh.curv: " + std::to_string(n) + " values for a surface of 42 vertices"));
}
