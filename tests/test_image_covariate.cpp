// A reference whose elements model a second feature of the subjects (Reference::image_covariate,
// vpm compare --image-covariate): the per-element slope fitted, a structural deviation that the
// plain reference reads as a focus explained away, a loss of function hidden by the structural
// spread found, and the command line (recorded in the sidecar, checked by calibrations).
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <set>
#include <string>

#include "support/elements.hpp"
#include "support/fixtures.hpp"
#include "support/process.hpp"
#include "vpm/calibration.hpp"
#include "vpm/error.hpp"
#include "vpm/json.hpp"
#include "vpm/statistics.hpp"

using namespace vpm;

namespace {

// The slope of "pet" on "t1w" at element e: -1.5 or +1.0, alternating (partial volumes of grey
// matter against white matter or against CSF).
double slope(int e) { return e % 2 ? 1.0 : -1.5; }

// A subject whose "t1w" varies by N(0, 5) per element around 50 (a registration's residual
// misalignment), shifted by `shift` on `where`, and whose "pet" follows it:
// 100 + slope (t1w - 50) + N(0, 1), minus `loss` on `where`.
ElementTable subject(const std::string& id, unsigned seed, const std::set<int>& where = {}, double shift = 0,
                     double loss = 0) {
  const CanonicalElements el(test::small_elements());
  ElementTable t;
  t.definition = el.definition();
  t.subject = id;
  ElementFeature pet, t1w;
  pet.name = "pet";
  t1w.name = "t1w";
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  for (int e = 0; e < el.size(); ++e) {
    const bool in = where.count(e) > 0;
    const double s = 50 + 5 * g(rng) + (in ? shift : 0);
    t1w.mean.push_back(s);
    pet.mean.push_back(100 + slope(e) * (s - 50) + g(rng) - (in ? loss : 0));
    for (ElementFeature* f : {&pet, &t1w}) {
      f->std.push_back(1);
      f->count.push_back(8);
    }
  }
  t.features = {pet, t1w};
  return t;
}

std::vector<ElementTable> normals(std::vector<std::string>& names) {
  std::vector<ElementTable> out;
  for (int i = 0; i < 20; ++i) {
    names.push_back("sub-N" + std::to_string(i));
    out.push_back(subject(names.back(), 200 + i));
  }
  return out;
}

// whether a focus of `cmp` touches `where`
bool found(const Comparison& cmp, const std::set<int>& where) {
  for (const FocusCluster& f : cmp.clusters)
    for (int e : f.elements)
      if (where.count(e)) return true;
  return false;
}

}  // namespace

TEST_CASE("image covariate: the slope per element, structure explained away, a loss hidden by it found") {
  const CanonicalElements el(test::small_elements());
  std::vector<std::string> names;
  const std::vector<ElementTable> ns = normals(names);
  const Reference plain = build_reference(el, ns, names, "pet", Normalisation::none, 0);
  const Reference model = build_reference(el, ns, names, "pet", Normalisation::none, 0, 0, {}, "t1w");
  REQUIRE(model.model_columns() == 2);
  REQUIRE(model.image_covariate == "t1w");
  // the fitted slopes follow the planted ones; the residual spread is the noise's, not the structure's
  double worst_slope = 0, mean_std = 0;
  for (int e = 0; e < el.size(); ++e) {
    worst_slope = std::max(worst_slope, std::abs(model.coefficients[2 * e + 1] - slope(e)));
    mean_std += model.std[e] / el.size();
    CHECK(std::abs(model.image_covariate_centre[e] - 50) < 5);
  }
  CHECK(worst_slope < 0.25);
  CHECK(mean_std > 0.8);
  CHECK(mean_std < 1.2);
  CompareOptions o;
  o.min_cluster = 2;
  o.sign = -1;
  const std::set<int> focus = test::planted_focus(el, 40);
  // misaligned structure (t1w 5 sds off) and the function that follows it: a focus for the plain
  // reference where pet falls with t1w (slope -1.5), nothing with the model
  const ElementTable shifted = subject("sub-S", 31, focus, 25.0);
  const Comparison s_plain = compare_to_reference(el, plain, shifted, o);
  const Comparison s_model = compare_to_reference(el, model, shifted, o);
  CHECK(found(s_plain, focus));
  CHECK(s_model.clusters.empty());
  // a true loss of 5 noise sds with normal structure: within the structural spread (z about -1)
  // for the plain reference, plain to see with the model
  const ElementTable lost = subject("sub-L", 32, focus, 0.0, 5.0);
  CHECK_FALSE(found(compare_to_reference(el, plain, lost, o), focus));
  const Comparison l_model = compare_to_reference(el, model, lost, o);
  CHECK(found(l_model, focus));
  CHECK(l_model.clusters.size() == 1);
  // the expected value is the patient's own prediction: below the normals' mean where its t1w is
  // high and the slope negative
  const int e0 = *focus.begin();
  CHECK(s_model.expected[e0] - model.mean[e0] == Approx(model.coefficients[2 * e0 + 1] *
                                                        (shifted.features[1].mean[e0] - model.image_covariate_centre[e0])));
}

TEST_CASE("image covariate: refused when it is the feature itself or a table lacks it") {
  const CanonicalElements el(test::small_elements());
  std::vector<std::string> names;
  std::vector<ElementTable> ns = normals(names);
  CHECK_THROWS_WITH(build_reference(el, ns, names, "pet", Normalisation::none, 0, 0, {}, "pet"),
                    Catch::Contains("the image covariate 'pet' is the feature compared itself"));
  ns[3].features.pop_back();
  CHECK_THROWS_WITH(build_reference(el, ns, names, "pet", Normalisation::none, 0, 0, {}, "t1w"),
                    Catch::Contains("sub-N3: no feature 't1w'"));
  names.clear();
  ns = normals(names);
  const Reference model = build_reference(el, ns, names, "pet", Normalisation::none, 0, 0, {}, "t1w");
  ElementTable p = subject("sub-P", 33);
  p.features.pop_back();
  CHECK_THROWS_AS(compare_to_reference(el, model, p), InputError);
}

TEST_CASE("vpm compare and calibrate --image-covariate: recorded in the sidecar, checked against calibrations") {
  const std::string dir = std::string(VPM_TEST_TMP) + "/imgcov_cli_";
  std::vector<std::string> names;
  const std::vector<ElementTable> ns = normals(names);
  std::string list;
  for (size_t i = 0; i < ns.size(); ++i) {
    write_subject_table(dir + names[i] + ".tsv", ns[i]);
    list += (i ? "," : "") + dir + names[i] + ".tsv";
  }
  const CanonicalElements el(test::small_elements());
  write_subject_table(dir + "s.tsv", subject("sub-S", 31, test::planted_focus(el, 40), 25.0));
  const std::string vpm = VPM_BINARY, base = " --feature pet --normalisation none --sign hypo --min-cluster 2 --normals " +
                                             list + " --quiet --patient " + dir + "s.tsv";
  REQUIRE(test::run_status(vpm + " compare" + base + " -o " + dir + "plain.tsv") == 0);
  REQUIRE(test::run_status(vpm + " compare" + base + " --image-covariate t1w -o " + dir + "model.tsv") == 0);
  const Json plain = Json::parse(test::slurp(dir + "plain.json")), model = Json::parse(test::slurp(dir + "model.json"));
  CHECK(plain.find("reference")->find("image_covariate") == nullptr);
  CHECK(model.find("reference")->find("image_covariate")->string() == "t1w");
  CHECK(plain.find("result")->find("clusters")->size() >= 1);
  CHECK(model.find("result")->find("clusters")->size() == 0);
  CHECK(test::run_status(vpm + " compare" + base + " --image-covariate pet -o " + dir + "bad.tsv 2> " + dir + "err.txt") == 2);
  CHECK_THAT(test::slurp(dir + "err.txt"), Catch::Contains("option --image-covariate: 'pet' must name another feature"));
  CHECK(test::run_status(vpm + " compare" + base + " --image-covariate fa -o " + dir + "bad.tsv 2> " + dir + "err2.txt") == 2);
  CHECK_THAT(test::slurp(dir + "err2.txt"), Catch::Contains("no feature 'fa'"));
  // a calibration made with the covariate applies to comparisons with it, not to those without
  const std::string cal = " --feature pet --normalisation none --sign hypo --normals " + list + " --quiet";
  REQUIRE(test::run_status(vpm + " calibrate" + cal + " --image-covariate t1w -o " + dir + "cal.json") == 0);
  CHECK(Json::parse(test::slurp(dir + "cal.json")).find("image_covariate")->string() == "t1w");
  CHECK(test::run_status(vpm + " compare --feature pet --normalisation none --sign hypo --normals " + list + " --patient " +
                         dir + "s.tsv --quiet --image-covariate t1w --min-cluster-from " + dir + "cal.json -o " + dir +
                         "cal_out.tsv") == 0);
  CHECK(test::run_status(vpm + " compare --feature pet --normalisation none --sign hypo --normals " + list + " --patient " +
                         dir + "s.tsv --quiet --min-cluster-from " + dir + "cal.json -o " + dir + "bad.tsv 2> " + dir +
                         "err3.txt") == 2);
  CHECK_THAT(test::slurp(dir + "err3.txt"), Catch::Contains("calibrated with image covariate 't1w'"));
}
