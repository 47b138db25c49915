// The peak rule's level calibrated on the normals (CalibrationSettings::calibrate_peak, vpm
// calibrate --peak auto): at most half the rate's false clusters peak beyond it, the cluster size
// then holds the whole rate with it, a small strong focus under that size is found by it, and the
// level travels through the calibration file to vpm compare --min-cluster-from.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <functional>
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

using namespace vpm;

namespace {

ElementTable subject(const std::string& id, unsigned seed, const std::set<int>& focus = {}, double loss = 0) {
  return test::noisy_pet_table(id, seed, focus, loss);
}

std::vector<ElementTable> normals(std::vector<std::string>& names) {
  std::vector<ElementTable> out;
  for (int i = 0; i < 10; ++i) {
    names.push_back("sub-N" + std::to_string(i));
    out.push_back(subject(names.back(), 300 + static_cast<unsigned>(i)));
  }
  return out;
}

CalibrationSettings settings() {
  CalibrationSettings s;
  s.feature = "pet";
  s.normalisation = Normalisation::none;
  s.compare.threshold = 2.2;  // low: false clusters of several sizes in the normals
  s.compare.extend = 1.5;
  s.compare.sign = -1;
  s.rate = 2;  // 2 per 10 normals: 2 clusters, 1 of them for the peak rule
  s.calibrate_peak = true;
  return s;
}

// The strongest of the left-out normals' cluster peaks the calibration kept, strongest first.
std::vector<double> peaks(const ClusterCalibration& c) {
  std::vector<double> p;
  for (const StrongCluster& s : c.strong) p.push_back(std::abs(s.peak_z));
  return p;
}

}  // namespace

TEST_CASE("calibrated peak: half the rate beyond the level, the size holds the rest, a small strong focus found") {
  const CanonicalElements el(test::small_elements());
  std::vector<std::string> names;
  const std::vector<ElementTable> n = normals(names);
  const CalibrationSettings s = settings();
  const ClusterCalibration cal = calibrate_min_cluster(el, n, names, s);
  const std::vector<double> p = peaks(cal);
  // every cluster counted once in the sizes; the two strongest kept (k + 1, k = 1), in order
  long total = 0;
  for (long v : cal.sizes) total += v;
  REQUIRE(total >= 3);
  REQUIRE(p.size() == 2);
  CHECK(p[0] >= p[1]);
  int listed = 0;
  for (const LeftOutNormal& x : cal.per_normal) listed += x.clusters;
  CHECK(listed == total);
  // one cluster (half of 2 per 10 over 10 normals) may peak beyond the level: strictly past the second
  CHECK(cal.peak > p[1]);
  CHECK(cal.peak <= p[1] + 0.01 + 1e-12);
  CHECK(std::count_if(p.begin(), p.end(), [&](double z) { return z >= cal.peak; }) <= 1);
  // the size holds the whole rate with the peak rule applied, and is the smallest that does
  REQUIRE(cal.min_cluster >= 1);
  CHECK(cal.rate_at(cal.min_cluster) <= s.rate);
  if (cal.min_cluster > 1) CHECK(cal.rate_at(cal.min_cluster - 1) > s.rate);
  // the count is what the comparisons with that rule give
  int direct = 0;
  CompareOptions rule = s.compare;
  rule.min_cluster = cal.min_cluster;
  rule.peak = cal.peak;
  for (size_t i = 0; i < n.size(); ++i) {
    const Reference ref = test::reference_without(el, n, names, i, s.normalisation);
    direct += static_cast<int>(compare_to_reference(el, ref, n[i], rule).clusters.size());
  }
  CHECK(direct == cal.clusters_at(cal.min_cluster));
  // a single element 12 spreads low: a focus by its peak, not by its size
  const Reference ref = build_reference(el, n, names, "pet", s.normalisation, 0);
  const int e0 = el.size() / 2;
  const ElementTable patient = subject("sub-P", 999, {e0}, 60);
  CompareOptions size_only = rule;
  size_only.peak = 0;
  size_only.min_cluster = std::max(cal.min_cluster, 2);
  rule.min_cluster = size_only.min_cluster;
  const auto has = [&](const Comparison& c) { return c.cluster[static_cast<size_t>(e0)] > 0; };
  CHECK_FALSE(has(compare_to_reference(el, ref, patient, size_only)));
  CHECK(has(compare_to_reference(el, ref, patient, rule)));
}

TEST_CASE("calibrated peak: through the file to the comparison, refused with a fixed level") {
  const CanonicalElements el(test::small_elements());
  std::vector<std::string> names;
  const std::vector<ElementTable> n = normals(names);
  const CalibrationSettings s = settings();
  const ClusterCalibration cal = calibrate_min_cluster(el, n, names, s);
  const Json j = to_json(cal);
  CHECK(j.find("calibrate_peak")->boolean());
  CHECK(j.find("options")->find("peak")->number() == 0);
  // the comparison's settings: the fixed peak 0, no calibration of its own
  CalibrationSettings compare = s;
  compare.calibrate_peak = false;
  const CalibratedRule rule = calibrated_rule(j, compare, names, "cal.json");
  CHECK(rule.min_cluster == cal.min_cluster);
  CHECK(rule.peak == cal.peak);
  // a comparison with a fixed level of its own is refused; a fixed level cannot be calibrated
  CalibrationSettings fixed = compare;
  fixed.compare.peak = 5;
  CHECK_THROWS_WITH(calibrated_rule(j, fixed, names, "cal.json"), Catch::Contains("options.peak"));
  CalibrationSettings both = s;
  both.compare.peak = 5;
  CHECK_THROWS_AS(calibrate_min_cluster(el, n, names, both), InputError);
  // without a calibrated peak (and in files from before it): the comparison's own level
  CalibrationSettings plain = compare;
  const ClusterCalibration size_only = calibrate_min_cluster(el, n, names, plain);
  CHECK(size_only.peak == 0);
  const Json old = to_json(size_only);
  CHECK(calibrated_rule(old, plain, names, "cal.json").peak == 0);
  Json bad = j;
  bad["peak"] = -1.0;
  CHECK_THROWS_WITH(calibrated_rule(bad, compare, names, "cal.json"), Catch::Contains("\"peak\""));
}

TEST_CASE("calibration: each normal's largest and strongest cluster, and a focus's family-wise p-value from them") {
  const CanonicalElements el(test::small_elements());
  std::vector<std::string> names;
  const std::vector<ElementTable> n = normals(names);
  const CalibrationSettings s = settings();
  const ClusterCalibration cal = calibrate_min_cluster(el, n, names, s);
  CalibrationSettings compare = s;
  compare.calibrate_peak = false;
  const CalibratedRule rule = calibrated_rule(to_json(cal), compare, names, "cal.json");
  REQUIRE(rule.cluster_null.size() == n.size());
  CompareOptions all = s.compare;
  all.min_cluster = 1;
  int with_clusters = 0;
  for (size_t i = 0; i < n.size(); ++i) {
    const Reference ref = test::reference_without(el, n, names, i, s.normalisation);
    Comparison c = compare_to_reference(el, ref, n[i], all);
    // the normal's largest and strongest cluster are those of its direct comparison
    int largest = 0;
    double strongest = 0;
    for (const FocusCluster& f : c.clusters) largest = std::max(largest, f.candidates), strongest = std::max(strongest, std::abs(f.peak_z));
    INFO(names[i]);
    CHECK(cal.per_normal[i].largest == largest);
    CHECK(cal.per_normal[i].strongest == Approx(strongest).epsilon(1e-12));
    CHECK(rule.cluster_null[i].first == largest);
    with_clusters += largest > 0;
    // each of its clusters: the smaller of its two ranks among the normals (larger ones, stronger
    // ones), and 1 + the normals whose own smaller rank is at or below it, over 11; its own
    // largest cluster counts the normal itself
    family_p_values(c, rule);
    const auto rank = [&](double size, double peak) {
      int larger = 0, stronger = 0;
      for (const LeftOutNormal& m : cal.per_normal) larger += m.largest >= size, stronger += m.strongest >= peak;
      return std::min(larger, stronger);
    };
    for (const FocusCluster& f : c.clusters) {
      int below = 0;
      for (const LeftOutNormal& m : cal.per_normal) below += rank(m.largest, m.strongest) <= rank(f.candidates, std::abs(f.peak_z));
      CHECK(f.p_family == Approx((1.0 + below) / 11));
      if (f.candidates == largest) CHECK(f.p_family >= 2.0 / 11);
    }
  }
  REQUIRE(with_clusters >= 2);
  // a patient's loss far beyond every normal: p = 1 / 11
  const Reference ref = build_reference(el, n, names, "pet", s.normalisation, 0);
  const int e0 = el.size() / 2;
  Comparison c = compare_to_reference(el, ref, subject("sub-P", 999, test::planted_focus(el, e0), 60), all);
  REQUIRE(c.cluster[static_cast<size_t>(e0)] > 0);
  family_p_values(c, rule);
  CHECK(c.clusters[static_cast<size_t>(c.cluster[static_cast<size_t>(e0)] - 1)].p_family == Approx(1.0 / 11));
  // a file from before these fields gives no p-value; a malformed one is refused
  Json old = to_json(cal), bad = to_json(cal), infinite = to_json(cal);
  Json per = Json::array(), broken = Json::array(), inf_per = Json::array();
  for (size_t i = 0; i < old.find("per_normal")->size(); ++i) {
    Json o = Json::object(), b = old.find("per_normal")->at(i), f = b;
    o["normal"] = b.find("normal")->string();
    o["clusters"] = b.find("clusters")->number();
    per.push_back(o);
    if (i == 3) b["largest"] = -2.0;
    broken.push_back(b);
    if (i == 0) f["strongest"] = Json::parse("null");  // how an infinite |z| is written
    inf_per.push_back(f);
  }
  old["per_normal"] = per;
  bad["per_normal"] = broken;
  infinite["per_normal"] = inf_per;
  CHECK(std::isinf(calibrated_rule(Json::parse(infinite.dump(-1)), compare, names, "inf.json").cluster_null[0].second));
  const CalibratedRule none = calibrated_rule(old, compare, names, "old.json");
  CHECK(none.cluster_null.empty());
  Comparison fresh = compare_to_reference(el, ref, subject("sub-P", 999, test::planted_focus(el, e0), 60), all);
  family_p_values(fresh, none);
  for (const FocusCluster& f : fresh.clusters) CHECK(f.p_family == -1);
  CHECK_THROWS_WITH(calibrated_rule(bad, compare, names, "bad.json"), Catch::Contains("bad.json: per_normal[3]"));
}

TEST_CASE("vpm calibrate --peak auto and vpm compare --min-cluster-from: the level recorded and applied") {
  const std::string dir = std::string(VPM_TEST_TMP) + "/cpeak_";
  std::vector<std::string> names;
  const std::vector<ElementTable> n = normals(names);
  std::string list;
  for (size_t i = 0; i < n.size(); ++i) {
    write_subject_table(dir + names[i] + ".tsv", n[i]);
    list += (i ? "," : "") + dir + names[i] + ".tsv";
  }
  const CanonicalElements el(test::small_elements());
  write_subject_table(dir + "p.tsv", subject("sub-P", 999, {el.size() / 2}, 60));
  const std::string vpm = VPM_BINARY,
                    opts = " --feature pet --normalisation none --threshold 2.2 --extend 1.5 --sign hypo --quiet";
  REQUIRE(test::run_status(vpm + " calibrate --normals " + list + opts + " --peak auto --rate 2 -o " + dir + "cal.json") == 0);
  const Json cal = Json::parse(test::slurp(dir + "cal.json"));
  CHECK(cal.find("calibrate_peak")->boolean());
  const double level = cal.find("peak")->number();
  CHECK(level > 2.2);
  REQUIRE(test::run_status(vpm + " compare --normals " + list + " --patient " + dir + "p.tsv" + opts +
                           " --min-cluster-from " + dir + "cal.json -o " + dir + "out.tsv") == 0);
  const Json side = Json::parse(test::slurp(dir + "out.json"));
  CHECK(side.find("options")->find("peak")->number() == level);
  // a fixed --peak beside a calibrated one, or auto outside vpm calibrate: exit 2 naming it
  const std::string err = dir + "err.txt";
  CHECK(test::run_status(vpm + " compare --normals " + list + " --patient " + dir + "p.tsv" + opts +
                         " --peak 4 --min-cluster-from " + dir + "cal.json -o " + dir + "bad.tsv 2> " + err) == 2);
  CHECK_THAT(test::slurp(err), Catch::Contains("options.peak"));
  CHECK(test::run_status(vpm + " compare --normals " + list + " --patient " + dir + "p.tsv" + opts +
                         " --peak auto --min-cluster 3 -o " + dir + "bad.tsv 2> " + err) == 2);
  CHECK_THAT(test::slurp(err), Catch::Contains("--peak"));
  CHECK(test::run_status("test -e " + dir + "bad.tsv") == 1);
}
