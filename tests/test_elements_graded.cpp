// The graded element layout (vpm/elements.hpp): equal volumes, near-cubic shapes at every depth,
// ids over mixed levels, adjacency across levels, samples and point lookup, definitions.
#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <set>

#include "support/process.hpp"
#include "vpm/elements.hpp"
#include "vpm/error.hpp"

using namespace vpm;

namespace {

ElementDefinition graded(int level, int samples = 1) {
  ElementDefinition d;
  d.layout = ElementLayout::graded;
  d.level = level;
  d.shells = graded_shells(level);
  d.samples = samples;
  return d;
}

// Direction d in triangle f of icosphere(l) (with a round-off margin).
bool in_triangle(const CanonicalElements& el, int l, int f, const Eigen::Vector3d& d, double eps = 1e-9) {
  const auto& s = el.sphere(l);
  Eigen::Vector3d v[3];
  for (int k = 0; k < 3; ++k) v[k] = s.vertices.row(s.triangles(f, k)).transpose();
  for (int k = 0; k < 3; ++k)
    if (v[k].cross(v[(k + 1) % 3]).dot(d) < -eps) return false;
  return true;
}

}  // namespace

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
      CHECK(in_triangle(el, el.shell_level(k), el.triangle_of(e), x.normalized()));
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
