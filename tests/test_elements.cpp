// Canonical volume elements (vpm/elements.hpp): ids, exact volumes, adjacency, sample points
// inside their element and uniform in volume, point -> element lookup, definitions; for both
// layouts (shells and graded).
#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <cmath>
#include <algorithm>
#include <set>
#include <string>

#include "vpm/elements.hpp"
#include "vpm/error.hpp"
#include "support/process.hpp"

using namespace vpm;

namespace {
// Direction d in the spherical triangle f of icosphere(level) (default: the elements' finest,
// sphere()), with a round-off margin.
bool in_triangle(const CanonicalElements& el, int f, const Eigen::Vector3d& d, double eps = 1e-12, int level = -1) {
  const auto& s = level < 0 ? el.sphere() : el.sphere(level);
  Eigen::Vector3d v[3];
  for (int k = 0; k < 3; ++k) v[k] = s.vertices.row(s.triangles(f, k)).transpose();
  for (int k = 0; k < 3; ++k)
    if (v[k].cross(v[(k + 1) % 3]).dot(d) < -eps) return false;
  return true;
}

ElementDefinition graded(int level, int samples = 1) {
  ElementDefinition d;
  d.layout = ElementLayout::graded;
  d.level = level;
  d.shells = graded_shells(level);
  d.samples = samples;
  return d;
}
}  // namespace

TEST_CASE("elements: ids, counts and exact volumes that fill the ball") {
  for (auto [level, shells] : {std::pair{0, 1}, {1, 3}, {3, 8}}) {
    INFO("level " << level << ", shells " << shells);
    ElementDefinition d;
    d.level = level;
    d.shells = shells;
    d.samples = 4;
    const CanonicalElements el(d);
    CHECK(el.triangles() == (20 << (2 * level)));
    CHECK(el.size() == el.triangles() * shells);
    double total = 0;
    for (int e = 0; e < el.size(); ++e) {
      CHECK(el.id(el.shell_of(e), el.triangle_of(e)) == e);
      CHECK(el.volume(e) > 0);
      total += el.volume(e);
    }
    CHECK(total == Approx(4 * M_PI / 3).epsilon(1e-12));
    CHECK(el.radius(0) == 0);
    CHECK(el.radius(shells) == Approx(1));
    // equal-volume shells: every shell holds 1/K of the ball
    double shell0 = 0;
    for (int f = 0; f < el.triangles(); ++f) shell0 += el.volume(el.id(0, f));
    CHECK(shell0 == Approx(4 * M_PI / 3 / shells).epsilon(1e-12));
    const ElementVolumeStats st = el.volume_stats();
    CHECK(st.mean == Approx(4 * M_PI / 3 / el.size()));
    CHECK(st.min <= st.mean * (1 + 1e-12));
    CHECK(st.max >= st.mean * (1 - 1e-12));
    if (level == 0) CHECK(st.std_relative < 1e-12);  // the icosahedron's faces are congruent
    if (level == 3) CHECK(st.max / st.min < 2.0);
  }
}

TEST_CASE("elements: adjacency is symmetric: three neighbours in the shell, one each side across shells") {
  ElementDefinition d;
  d.level = 2;
  d.shells = 3;
  d.samples = 1;
  const CanonicalElements el(d);
  for (int e = 0; e < el.size(); ++e) {
    const auto nb = el.neighbours(e);
    const int k = el.shell_of(e);
    CHECK(nb.size() == static_cast<size_t>(3 + (k > 0) + (k + 1 < 3)));
    CHECK(std::set<int>(nb.begin(), nb.end()).size() == nb.size());
    for (int n : nb) {
      const auto back = el.neighbours(n);
      CHECK(std::find(back.begin(), back.end(), e) != back.end());
      if (el.shell_of(n) == k) {  // same shell: the triangles share an edge
        int shared = 0;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            shared += el.sphere().triangles(el.triangle_of(e), i) == el.sphere().triangles(el.triangle_of(n), j);
        CHECK(shared == 2);
      } else {
        CHECK(el.triangle_of(n) == el.triangle_of(e));
      }
    }
  }
}

TEST_CASE("elements: samples lie in their element, are uniform in volume and the same every time") {
  ElementDefinition d;
  d.level = 1;
  d.shells = 2;
  d.samples = 2048;
  const CanonicalElements el(d);
  const Points& p = el.samples();
  REQUIRE(p.rows() == static_cast<Eigen::Index>(el.size()) * d.samples);
  for (int e = 0; e < el.size(); e += 7) {
    const int k = el.shell_of(e), f = el.triangle_of(e);
    const double r0 = el.radius(k), r1 = el.radius(k + 1);
    double mean_r3 = 0;
    // the triangle split at its edge midpoints: each quarter gets samples in proportion to its area
    const auto& s = el.sphere();
    Eigen::Vector3d v[3];
    for (int i = 0; i < 3; ++i) v[i] = s.vertices.row(s.triangles(f, i)).transpose();
    const Eigen::Vector3d m01 = (v[0] + v[1]).normalized(), m12 = (v[1] + v[2]).normalized(),
                          m20 = (v[2] + v[0]).normalized();
    auto omega = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
      return 2 * std::atan2(a.dot(b.cross(c)), 1 + a.dot(b) + b.dot(c) + c.dot(a));
    };
    const double corner_area = omega(v[0], m01, m20), total_area = omega(v[0], v[1], v[2]);
    int in_corner = 0;
    for (int i = 0; i < d.samples; ++i) {
      const Eigen::Vector3d x = p.row(static_cast<Eigen::Index>(e) * d.samples + i).transpose();
      const double r = x.norm();
      CHECK(r >= r0 - 1e-12);
      CHECK(r <= r1 + 1e-12);
      CHECK(in_triangle(el, f, x / r, 1e-9));
      CHECK(el.element_of(x) == e);
      mean_r3 += r * r * r / d.samples;
      const Eigen::Vector3d dir = x / r;
      in_corner += v[0].cross(m01).dot(dir) >= 0 && m01.cross(m20).dot(dir) >= 0 && m20.cross(v[0]).dot(dir) >= 0;
    }
    CHECK(mean_r3 == Approx(0.5 * (r0 * r0 * r0 + r1 * r1 * r1)).epsilon(0.01));
    CHECK(double(in_corner) / d.samples == Approx(corner_area / total_area).margin(0.01));
  }
  const CanonicalElements again(d);
  CHECK(again.samples() == p);
}

TEST_CASE("elements: element_of finds the element of any ball point") {
  ElementDefinition d;
  d.level = 3;
  d.shells = 8;
  d.samples = 1;
  const CanonicalElements el(d);
  std::srand(7);
  for (int i = 0; i < 2000; ++i) {
    Eigen::Vector3d x = Eigen::Vector3d::Random();
    if (x.norm() > 1) continue;
    const int e = el.element_of(x);
    REQUIRE(e >= 0);
    const double r = x.norm();
    CHECK(r >= el.radius(el.shell_of(e)) - 1e-12);
    CHECK(r <= el.radius(el.shell_of(e) + 1) + 1e-12);
    CHECK(in_triangle(el, el.triangle_of(e), x / r));
  }
  CHECK(el.element_of(Eigen::Vector3d(0, 0, 1.01)) == -1);
  CHECK(el.element_of(Eigen::Vector3d(0, 0, 1)) >= 0);
  CHECK(el.element_of(Eigen::Vector3d::Zero()) >= 0);
}

TEST_CASE("elements: definitions round-trip through JSON and bad ones are refused") {
  ElementDefinition d;
  d.level = 4;
  d.shells = 16;
  d.samples = 32;
  CHECK(element_definition_from_json(to_json(d), "t.json") == d);
  CHECK(d != ElementDefinition{});
  Json j = to_json(d);
  j["generator_version"] = 99;
  CHECK_THROWS_WITH(element_definition_from_json(j, "t.json"), Catch::Contains("t.json") && Catch::Contains("version 99"));
  Json k = to_json(d);
  k["shells"] = 0;
  CHECK_THROWS_WITH(element_definition_from_json(k, "t.json"), Catch::Contains("shells 0"));
  ElementDefinition bad;
  bad.level = 8;
  CHECK_THROWS_AS(CanonicalElements(bad), InputError);
}

TEST_CASE("vpm elements writes the element table and its sidecar, bad values exit 2") {
  const std::string dir = VPM_TEST_TMP;
  const std::string tsv = dir + "/elements_l1.tsv";
  REQUIRE(test::run_status(std::string(VPM_BINARY) + " elements -o " + tsv + " --level 1 --shells 2 --quiet") == 0);
  const std::string text = test::slurp(tsv);
  CHECK_THAT(text, Catch::StartsWith("element\tshell\ttriangle\tvolume\tcentre_x\tcentre_y\tcentre_z\n"));
  CHECK(std::count(text.begin(), text.end(), '\n') == 1 + 80 * 2);
  const Json side = Json::parse(test::slurp(dir + "/elements_l1.json"));
  ElementDefinition d;
  d.level = 1;
  d.shells = 2;
  CHECK(element_definition_from_json(*side.find("definition"), "sidecar") == d);
  CHECK(side.find("elements")->number() == 160);
  CHECK(test::run_status(std::string(VPM_BINARY) + " elements -o " + dir + "/bad.tsv --level 9 2>/dev/null") == 2);
  CHECK(test::run_status(std::string(VPM_BINARY) + " elements 2>/dev/null") == 2);
}

// ---- the graded layout: equal volumes, near-cubic shapes at every depth, ids over mixed levels,
// adjacency across levels, samples and point lookup, definitions

TEST_CASE("graded elements: equal volumes filling the ball, coarser levels inward, near-cubic everywhere") {
  CHECK(graded_shells(3) == 9);
  CHECK(graded_shells(4) == 19);
  for (int level : {0, 2, 3, 4}) {
    INFO("level " << level);
    const CanonicalElements el(graded(level));
    const int K = el.definition().shells;
    CHECK(el.size() == el.definition().elements());
    CHECK(el.shell_level(K - 1) == level);
    CHECK(el.shell_level(0) == 0);
    double total = 0;
    for (int e = 0; e < el.size(); ++e) total += el.volume(e);
    CHECK(total == Approx(4 * M_PI / 3).epsilon(1e-12));
    // every shell's elements have the ball's mean element volume (up to the triangles' spread)
    for (int k = 0; k < K; ++k) {
      double shell = 0;
      for (int f = 0; f < el.shell_triangles(k); ++f) shell += el.volume(el.id(k, f));
      CHECK(shell / el.shell_triangles(k) == Approx(4 * M_PI / 3 / el.size()).epsilon(1e-12));
      if (k > 0) CHECK(el.shell_level(k) >= el.shell_level(k - 1));
      // thickness against the width of the shell's triangles at its middle radius: equal volumes
      // make it go as r^-3 inside a level's band (a factor 2 in radius), so 1/sqrt(8)..sqrt(8)
      const double width = el.mid_radius(k) * std::sqrt(4 * M_PI / el.shell_triangles(k));
      const double thickness = el.radius(k + 1) - el.radius(k);
      if (K > 1) {
        CHECK(thickness / width > 0.35);
        CHECK(thickness / width < 2.83);
      }
    }
  }
  // the paper's layout at the same level: inner elements are cones many times longer than wide
  ElementDefinition s;
  s.level = 3;
  s.shells = 8;
  const CanonicalElements plain(s);
  CHECK(plain.radius(1) / (plain.mid_radius(0) * std::sqrt(4 * M_PI / plain.triangles())) > 4);
}

TEST_CASE("graded elements: ids, adjacency across levels, samples and lookup") {
  const CanonicalElements el(graded(3, 16));
  const int K = el.definition().shells;
  for (int e = 0; e < el.size(); ++e) {
    const int k = el.shell_of(e), f = el.triangle_of(e);
    REQUIRE(el.id(k, f) == e);
    REQUIRE(f < el.shell_triangles(k));
    const auto nb = el.neighbours(e);
    CHECK(std::set<int>(nb.begin(), nb.end()).size() == nb.size());
    for (int n : nb) {
      const auto back = el.neighbours(n);
      CHECK(std::find(back.begin(), back.end(), e) != back.end());
      const int kn = el.shell_of(n);
      CHECK(std::abs(kn - k) <= 1);
      if (kn != k) {  // across shells: one triangle is the other's ancestor
        const int fine = std::max(el.shell_level(k), el.shell_level(kn)), coarse = std::min(el.shell_level(k), el.shell_level(kn));
        const int ff = el.shell_level(k) == fine ? f : el.triangle_of(n), fc = el.shell_level(k) == fine ? el.triangle_of(n) : f;
        CHECK((ff >> (2 * (fine - coarse))) == fc);
      }
    }
    // the outermost triangles over this element map back to it
    const int d = 2 * (el.definition().level - el.shell_level(k));
    CHECK(el.id_over(k, f << d) == e);
    CHECK(el.id_over(k, ((f + 1) << d) - 1) == e);
  }
  // the element of the shell inside a level change has the 4 finer elements outside as neighbours
  for (int k = 0; k + 1 < K; ++k)
    if (el.shell_level(k + 1) > el.shell_level(k)) CHECK(el.neighbours(el.id(k, 0)).size() == 3 + (k > 0) + 4);
  const Points& p = el.samples();
  for (int e = 0; e < el.size(); e += 3)
    for (int i = 0; i < 16; ++i) {
      const Eigen::Vector3d x = p.row(static_cast<Eigen::Index>(e) * 16 + i).transpose();
      const int k = el.shell_of(e);
      CHECK(x.norm() >= el.radius(k) - 1e-12);
      CHECK(x.norm() <= el.radius(k + 1) + 1e-12);
      CHECK(in_triangle(el, el.triangle_of(e), x.normalized(), 1e-9, el.shell_level(k)));
      CHECK(el.element_of(x) == e);
    }
  CHECK(el.element_of(Eigen::Vector3d::Zero()) == 0);
  CHECK(el.element_of(Eigen::Vector3d(0, 0, 1)) >= el.size() - el.triangles());
}

TEST_CASE("graded elements: definitions name their layout, old tables read as shells, wrong shells are refused") {
  const ElementDefinition g = graded(4, 32);
  CHECK(element_definition_from_json(to_json(g), "t.json") == g);
  ElementDefinition s;  // shells at the same level and count differ from graded ones
  s.level = 4;
  s.shells = g.shells;
  s.samples = 32;
  CHECK(s != g);
  Json old = Json::object();  // as written before the layouts existed
  for (const char* key : {"level", "shells", "samples", "generator", "generator_version"}) old[key] = *to_json(s).find(key);
  CHECK(element_definition_from_json(old, "old.json") == s);
  Json wrong = to_json(g);
  wrong["shells"] = 8;
  CHECK_THROWS_WITH(element_definition_from_json(wrong, "w.json"), Catch::Contains("w.json") && Catch::Contains("19 shells"));
  Json unknown = to_json(g);
  unknown["layout"] = "spiral";
  CHECK_THROWS_WITH(element_definition_from_json(unknown, "u.json"), Catch::Contains("u.json") && Catch::Contains("spiral"));
  CHECK_THROWS_AS(parse_element_layout("cubes"), InputError);
}

TEST_CASE("vpm elements --layout graded: the table has the graded count, --shells with it exits 2") {
  const std::string dir = VPM_TEST_TMP;
  REQUIRE(test::run_status(std::string(VPM_BINARY) + " elements -o " + dir + "/graded_l2.tsv --layout graded --level 2 --quiet") == 0);
  const Json side = Json::parse(test::slurp(dir + "/graded_l2.json"));
  CHECK(side.find("elements")->number() == graded(2).elements());
  CHECK(side.find("definition")->find("layout")->string() == "graded");
  CHECK(test::run_status(std::string(VPM_BINARY) + " elements -o " + dir + "/bad.tsv --layout graded --shells 4 2>/dev/null") == 2);
  CHECK(test::run_status(std::string(VPM_BINARY) + " elements -o " + dir + "/bad.tsv --layout cubes 2>/dev/null") == 2);
}
