// Threshold-free cluster enhancement (vpm/tfce.hpp) and its calibration on the normals
// (CalibrationSettings::calibrate_tfce): the scores are the sum over heights of the component's
// size^E h^H dh (checked against a direct sweep), the level keeps at most the rate's normals over
// it, it travels through the calibration file to vpm compare, and a focus gets its p-value.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <string>

#include "support/elements.hpp"
#include "support/fixtures.hpp"
#include "support/process.hpp"
#include "vpm/calibration.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/statistics.hpp"
#include "vpm/tfce.hpp"

using namespace vpm;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The definition, directly: at every height h = dh, 2 dh, ..., each element's component of
// {sign z >= h} found by a search of its own.
std::vector<double> direct_tfce(const CanonicalElements& el, const std::vector<double>& z, int sign) {
  const TfceParameters p;
  std::vector<double> out(z.size(), 0);
  double top = 0;
  for (double v : z)
    if (!std::isnan(v)) top = std::max(top, sign * v);
  for (int k = 1; k * p.step <= top + 1e-9; ++k) {
    const double h = k * p.step;
    const auto in = [&](int e) { return !std::isnan(z[e]) && sign * z[e] >= h - 1e-12 * h; };
    std::vector<int> comp(z.size(), -1), size;
    for (int s = 0; s < el.size(); ++s) {
      if (comp[s] >= 0 || !in(s)) continue;
      const int id = static_cast<int>(size.size());
      size.push_back(0);
      std::vector<int> stack{s};
      comp[s] = id;
      while (!stack.empty()) {
        const int e = stack.back();
        stack.pop_back();
        ++size[id];
        for (int nb : el.adjacent(e))
          if (comp[nb] < 0 && in(nb)) comp[nb] = id, stack.push_back(nb);
      }
    }
    for (int e = 0; e < el.size(); ++e)
      if (comp[e] >= 0) out[e] += std::sqrt(double(size[comp[e]])) * h * h * p.step;
  }
  return out;
}

ElementTable subject(const std::string& id, unsigned seed, const std::set<int>& focus = {}, double loss = 0) {
  return test::noisy_pet_table(id, seed, focus, loss);
}

std::vector<ElementTable> normals(std::vector<std::string>& names) {
  std::vector<ElementTable> out;
  for (int i = 0; i < 10; ++i) {
    names.push_back("sub-N" + std::to_string(i));
    out.push_back(subject(names.back(), 500 + static_cast<unsigned>(i)));
  }
  return out;
}

CalibrationSettings settings() {
  CalibrationSettings s;
  s.feature = "pet";
  s.normalisation = Normalisation::none;
  s.compare.sign = -1;
  s.rate = 2;  // 2 per 10 normals: 2 of the 10 may pass the level
  s.calibrate_tfce = true;
  return s;
}

}  // namespace

TEST_CASE("tfce: the scores of one element, of two adjacent ones, and the sign") {
  const CanonicalElements el(test::small_elements());
  std::vector<double> z(el.size(), kNaN);
  const int a = 0, b = el.adjacent(0)[0];
  int far = -1;  // an element adjacent to neither
  for (int e = 1; e < el.size() && far < 0; ++e) {
    const auto na = el.adjacent(a), nb = el.adjacent(b);
    if (e != b && std::find(na.begin(), na.end(), e) == na.end() && std::find(nb.begin(), nb.end(), e) == nb.end())
      far = e;
  }
  REQUIRE(far > 0);
  z[a] = -0.35;
  z[far] = -0.35;
  const double one = (0.01 + 0.04 + 0.09) * 0.1;  // heights 0.1, 0.2, 0.3 of a component of 1
  std::vector<double> s = tfce_scores(el, z, -1);
  CHECK(s[a] == Approx(one).epsilon(1e-12));
  CHECK(s[far] == Approx(one).epsilon(1e-12));
  CHECK(s[b] == 0);
  CHECK(tfce_scores(el, z, 1)[a] == 0);  // the other sign
  z[b] = -0.35;
  s = tfce_scores(el, z, -1);
  CHECK(s[a] == Approx(std::sqrt(2.0) * one).epsilon(1e-12));
  CHECK(s[b] == Approx(std::sqrt(2.0) * one).epsilon(1e-12));
  CHECK(s[far] == Approx(one).epsilon(1e-12));
  CHECK_THROWS_AS(tfce_scores(el, std::vector<double>(3, 1.0), 1), InputError);
  CHECK_THROWS_AS(tfce_scores(el, z, 0), InputError);
}

TEST_CASE("tfce: a random map scores as the direct sweep, and an infinite z stays finite") {
  const CanonicalElements el(test::small_elements());
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0, 1.5);
  std::vector<double> z(el.size());
  for (double& v : z) v = g(rng);
  z[3] = kNaN;
  for (int sign : {1, -1}) {
    const std::vector<double> fast = tfce_scores(el, z, sign), slow = direct_tfce(el, z, sign);
    for (int e = 0; e < el.size(); ++e) {
      INFO("element " << e << ", sign " << sign);
      CHECK(fast[e] == Approx(slow[e]).epsilon(1e-9).margin(1e-12));
    }
  }
  z[5] = -std::numeric_limits<double>::infinity();
  for (double v : tfce_scores(el, z, -1)) CHECK(std::isfinite(v));
}

TEST_CASE("tfce calibration: at most the rate's normals over the level, a focus found with its p-value") {
  const CanonicalElements el(test::small_elements());
  std::vector<std::string> names;
  const std::vector<ElementTable> n = normals(names);
  const CalibrationSettings s = settings();
  const ClusterCalibration cal = calibrate_min_cluster(el, n, names, s);
  std::vector<double> maxima;
  for (const LeftOutNormal& x : cal.per_normal) maxima.push_back(x.tfce_max);
  std::sort(maxima.begin(), maxima.end(), std::greater<>());
  REQUIRE(maxima[2] > 0);
  CHECK(cal.tfce_level > maxima[2]);  // k = 2: strictly beyond the third
  CHECK(cal.tfce_level <= maxima[2] * (1 + 2e-5));
  // the comparisons with that level: at most 2 normals show a focus (and those with the highest maxima)
  CompareOptions rule = s.compare;
  rule.tfce_level = cal.tfce_level;
  int with_focus = 0;
  for (size_t i = 0; i < n.size(); ++i) {
    const Reference ref = test::reference_without(el, n, names, i, s.normalisation);
    const Comparison c = compare_to_reference(el, ref, n[i], rule);
    with_focus += !c.clusters.empty();
    CHECK(c.clusters.empty() == (cal.per_normal[i].tfce_max < cal.tfce_level));
  }
  CHECK(with_focus == 2);
  // a patient with a loss of 7 spreads on an element and its shell neighbours: one focus, all of it
  const int e0 = el.size() / 2;
  const std::set<int> focus = test::planted_focus(el, e0);
  const Reference ref = build_reference(el, n, names, "pet", s.normalisation, 0);
  Comparison c = compare_to_reference(el, ref, subject("sub-P", 999, focus, 35), rule);
  REQUIRE(c.cluster[e0] > 0);
  const FocusCluster& f = c.clusters[c.cluster[e0] - 1];
  CHECK(f.sign == -1);
  CHECK(f.peak_tfce >= cal.tfce_level);
  CHECK(f.peak_z == c.z[f.peak_element]);
  for (int e : focus) CHECK(c.cluster[e] == f.id);
  // through the file: the level and the null; the p-value of the focus beyond every normal
  CalibrationSettings compare = s;
  compare.calibrate_tfce = false;
  const Json j = to_json(cal);
  const CalibratedRule r = calibrated_rule(j, compare, names, "cal.json");
  CHECK(r.tfce_level == Approx(cal.tfce_level).epsilon(1e-9));
  REQUIRE(r.tfce_null.size() == 10);
  CHECK(r.tfce_null.front() == Approx(maxima.front()).epsilon(1e-9));
  family_p_values(c, r);
  CHECK(c.clusters[c.cluster[e0] - 1].p_family == Approx(1.0 / 11));
  Json bad = j;
  bad["tfce_level"] = 0.0;
  CHECK_THROWS_WITH(calibrated_rule(bad, compare, names, "cal.json"), Catch::Contains("tfce_level"));
  // no TFCE with a peak rule
  CalibrationSettings both = s;
  both.calibrate_peak = true;
  CHECK_THROWS_AS(calibrate_min_cluster(el, n, names, both), InputError);
}

TEST_CASE("vpm calibrate --tfce and vpm compare --min-cluster-from: the level applied, each focus's p-value") {
  const std::string dir = std::string(VPM_TEST_TMP) + "/tfce_";
  std::vector<std::string> names;
  const std::vector<ElementTable> n = normals(names);
  std::string list;
  for (size_t i = 0; i < n.size(); ++i) {
    write_subject_table(dir + names[i] + ".tsv", n[i]);
    list += (i ? "," : "") + dir + names[i] + ".tsv";
  }
  const CanonicalElements el(test::small_elements());
  write_subject_table(dir + "p.tsv", subject("sub-P", 999, test::planted_focus(el, el.size() / 2), 35));
  const std::string vpm = VPM_BINARY, opts = " --feature pet --normalisation none --sign hypo --quiet";
  REQUIRE(test::run_status(vpm + " calibrate --normals " + list + opts + " --tfce --rate 2 -o " + dir + "cal.json") == 0);
  const Json cal = Json::parse(test::slurp(dir + "cal.json"));
  CHECK(cal.find("tfce")->boolean());
  const double level = cal.find("tfce_level")->number();
  CHECK(level > 0);
  REQUIRE(test::run_status(vpm + " compare --normals " + list + " --patient " + dir + "p.tsv" + opts +
                           " --min-cluster-from " + dir + "cal.json -o " + dir + "out.tsv") == 0);
  const Json side = Json::parse(test::slurp(dir + "out.json"));
  CHECK(side.find("options")->find("tfce_level")->number() == level);
  const Json& clusters = *side.find("result")->find("clusters");
  REQUIRE(clusters.size() >= 1);
  CHECK(clusters.at(0).find("p_family")->number() == Approx(1.0 / 11));
  CHECK(clusters.at(0).find("peak_tfce")->number() >= level);
  // --tfce beside --peak, or a level of one's own beside a TFCE calibration: exit 2 naming it
  const std::string err = dir + "err.txt";
  CHECK(test::run_status(vpm + " calibrate --normals " + list + opts + " --tfce --peak auto -o " + dir + "bad.json 2> " + err) == 2);
  CHECK_THAT(test::slurp(err), Catch::Contains("--tfce"));
  CHECK(test::run_status(vpm + " compare --normals " + list + " --patient " + dir + "p.tsv" + opts + " --tfce-level 1 " +
                         "--min-cluster-from " + dir + "cal.json -o " + dir + "bad.tsv 2> " + err) == 2);
  CHECK_THAT(test::slurp(err), Catch::Contains("--tfce-level"));
  CHECK(test::run_status("test -e " + dir + "bad.tsv") == 1);
  CHECK(test::run_status("test -e " + dir + "bad.json") == 1);
}
