// A reference that models participant covariates (vpm/covariates.hpp, vpm/statistics.hpp): the
// participants table read and checked, the per-element least squares and the patient's
// prediction and leverage, a focus hidden by the age spread found with the model, and the
// command line (vpm compare / calibrate --covariates --participants).
#include <catch2/catch.hpp>
#include <Eigen/Dense>
#include <cmath>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include "support/elements.hpp"
#include "support/fixtures.hpp"
#include "support/process.hpp"
#include "vpm/covariates.hpp"
#include "vpm/error.hpp"
#include "vpm/json.hpp"
#include "vpm/statistics.hpp"

using namespace vpm;

namespace {

ElementDefinition def() { return test::small_elements(); }
using test::planted_focus;

const double kSlope = 0.3;  // per year
const double kMale = 2.0;

// A subject of `age` and `sex`: feature "pet" = 100 + kSlope (age - 50) + kMale [M] + N(0, 1),
// minus `loss` on the elements of `focus`.
ElementTable subject(const std::string& id, unsigned seed, double age, char sex, const std::set<int>& focus = {},
                     double loss = 0) {
  const CanonicalElements el(def());
  ElementTable t;
  t.definition = def();
  t.subject = id;
  ElementFeature f;
  f.name = "pet";
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  for (int e = 0; e < el.size(); ++e) {
    f.mean.push_back(100 + kSlope * (age - 50) + (sex == 'M' ? kMale : 0) + g(rng) - (focus.count(e) ? loss : 0));
    f.std.push_back(1);
    f.count.push_back(8);
  }
  t.features.push_back(f);
  return t;
}

struct Cohort {
  std::vector<ElementTable> normals;
  std::vector<std::string> names;
  std::string table;  // participants.tsv path
};

// 14 normals aged 20-80, alternating sex, and their participants table (plus P1, P2, P3).
Cohort cohort(const std::string& dir) {
  Cohort c;
  c.table = dir + "participants.tsv";
  std::ofstream out(c.table);
  out << "participant_id\tgroup\tage\tsex\n";
  for (int i = 0; i < 14; ++i) {
    const std::string id = "sub-N" + std::to_string(i);
    const double age = 20 + 60.0 * i / 13;
    const char sex = i % 2 ? 'M' : 'F';
    c.normals.push_back(subject(id, 100 + i, age, sex));
    c.names.push_back(id);
    out << id << "\tnormal\t" << age << '\t' << sex << '\n';
  }
  out << "sub-P1\tpatient\t35\tF\nsub-P2\tpatient\t85\tM\nsub-P3\tpatient\tn/a\tF\n";
  return c;
}

}  // namespace

TEST_CASE("covariates: the participants table read into design rows, bad tables refused with file and line") {
  const std::string dir = std::string(VPM_TEST_TMP) + "/cov_read_";
  const Cohort c = cohort(dir);
  const Covariates cov = read_covariates(c.table, {"age", "sex"});
  CHECK(cov.columns == std::vector<std::string>{"age", "sex=M"});
  CHECK(covariate_row(cov, "sub-P2", "p2.tsv") == std::vector<double>{85, 1});
  CHECK(covariate_row(cov, "sub-N0", "n0.tsv") == std::vector<double>{20, 0});
  const CovariateDesign d = covariate_design(cov, c.normals, c.names);
  CHECK(d.rows.size() == 14);
  CHECK(d.names == std::vector<std::string>{"age", "sex"});
  CHECK_THROWS_WITH(covariate_row(cov, "sub-P3", "p3.tsv"), Catch::Contains("no value for age") && Catch::Contains("p3.tsv"));
  CHECK_THROWS_WITH(covariate_row(cov, "sub-X", "x.tsv"), Catch::Contains("no row for participant 'sub-X'"));
  CHECK_THROWS_WITH(read_covariates(c.table, {"weight"}), Catch::Contains("participants.tsv:1: no column 'weight'"));
  CHECK_THROWS_AS(read_covariates(c.table, {"age", "age"}), InputError);
  std::ofstream(dir + "bad.tsv") << "participant_id\tage\nsub-1\t30\nsub-2\n";
  CHECK_THROWS_WITH(read_covariates(dir + "bad.tsv", {"age"}), Catch::Contains("bad.tsv:3: 1 cells where the header has 2"));
  std::ofstream(dir + "twice.tsv") << "participant_id\tage\nsub-1\t30\nsub-1\t31\n";
  CHECK_THROWS_WITH(read_covariates(dir + "twice.tsv", {"age"}), Catch::Contains("twice.tsv:3: participant_id 'sub-1' repeated"));
  // line numbers count the file's lines, blank ones included
  std::ofstream(dir + "blank.tsv") << "participant_id\tage\n\nsub-1\t30\n\nsub-1\t31\n";
  CHECK_THROWS_WITH(read_covariates(dir + "blank.tsv", {"age"}), Catch::Contains("blank.tsv:5: participant_id 'sub-1' repeated"));
  // a text covariate with one value in the whole table adjusts for nothing: refused, not dropped
  std::ofstream(dir + "one.tsv") << "participant_id\tsite\nsub-1\tA\nsub-2\tn/a\nsub-3\tA\n";
  CHECK_THROWS_WITH(read_covariates(dir + "one.tsv", {"site"}), Catch::Contains("one.tsv: covariate 'site' has the one value 'A'"));
  CHECK_THROWS_AS(read_covariates(dir + "missing.tsv", {"age"}), InputError);
}

TEST_CASE("covariates: per-element least squares, the patient's prediction and Crawford-Howell leverage") {
  const std::string dir = std::string(VPM_TEST_TMP) + "/cov_fit_";
  const Cohort c = cohort(dir);
  const CanonicalElements el(def());
  const Covariates cov = read_covariates(c.table, {"age", "sex"});
  const CovariateDesign d = covariate_design(cov, c.normals, c.names);
  const Reference ref = build_reference(el, c.normals, c.names, "pet", Normalisation::none, 0, 0, d);
  REQUIRE(ref.covariates == std::vector<std::string>{"age", "sex=M"});
  // the same fit by the normal equations, at a few elements
  Eigen::MatrixXd X(14, 3);
  for (int i = 0; i < 14; ++i) X.row(i) << 1, d.rows[i][0], d.rows[i][1];
  const ElementTable p2 = subject("sub-P2", 7, 85, 'M');
  const std::vector<double> row = covariate_row(cov, "sub-P2", "p2");
  CompareOptions ch;
  ch.test = SingleCaseTest::crawford_howell;
  const Comparison cz = compare_to_reference(el, ref, p2, {}, row);
  const Comparison cc = compare_to_reference(el, ref, p2, ch, row);
  for (int e : {0, 11, el.size() / 2, el.size() - 1}) {
    Eigen::VectorXd y(14);
    for (int i = 0; i < 14; ++i) y(i) = c.normals[i].features[0].mean[e];
    const Eigen::VectorXd b = (X.transpose() * X).ldlt().solve(X.transpose() * y);
    const double s = std::sqrt((y - X * b).squaredNorm() / (14 - 3));
    Eigen::Vector3d x(1, 85, 1);
    const double pred = x.dot(b), h = x.dot((X.transpose() * X).ldlt().solve(x));
    CHECK(cz.expected[e] == Approx(pred).epsilon(1e-10));
    CHECK(ref.std[e] == Approx(s).epsilon(1e-10));
    const double xe = p2.features[0].mean[e];
    CHECK(cz.z[e] == Approx((xe - pred) / (s * std::sqrt(1 + h - 1.0 / 14))).epsilon(1e-9));
    // Crawford-Howell: t = (x - pred) / (s sqrt(1 + h)) with 11 dof, as the z of its tail
    const double t = (xe - pred) / (s * std::sqrt(1 + h));
    CHECK(std::abs(cc.z[e]) <= std::abs(t) + 1e-12);  // t's tails are heavier: its z is smaller
    CHECK(cc.z[e] * t >= 0);
    // the slopes recovered (noise 1 over a 60-year span)
    CHECK(ref.coefficients[3 * e + 1] == Approx(kSlope).margin(0.08));
  }
  CHECK(cz.covariates == row);
  // without the row, or with one of another length: refused
  CHECK_THROWS_AS(compare_to_reference(el, ref, p2, {}), InputError);
  // a covariate constant over the normals cannot be modelled
  CovariateDesign flat = d;
  for (auto& r : flat.rows) r[1] = 1;
  CHECK_THROWS_WITH(build_reference(el, c.normals, c.names, "pet", Normalisation::none, 0, 0, flat),
                    Catch::Contains("do not vary independently"));
}

TEST_CASE("covariates: a focus the age spread hides is found with the model, an old patient without one stays clean") {
  const std::string dir = std::string(VPM_TEST_TMP) + "/cov_focus_";
  const Cohort c = cohort(dir);
  const CanonicalElements el(def());
  const Covariates cov = read_covariates(c.table, {"age", "sex"});
  const Reference plain = build_reference(el, c.normals, c.names, "pet", Normalisation::none, 0);
  const Reference model =
      build_reference(el, c.normals, c.names, "pet", Normalisation::none, 0, 0, covariate_design(cov, c.normals, c.names));
  CompareOptions o;
  o.min_cluster = 2;
  o.sign = -1;
  const std::set<int> focus = planted_focus(el, 40);
  // P1, 35, female: her values sit 4.5 + 1 below the cohort mean already; a loss of 5 (5 noise sds)
  const ElementTable p1 = subject("sub-P1", 11, 35, 'F', focus, 5.0);
  const Comparison without = compare_to_reference(el, plain, p1, o);
  const Comparison with = compare_to_reference(el, model, p1, o, covariate_row(cov, "sub-P1", "p1"));
  auto found = [&](const Comparison& cmp) {
    for (const FocusCluster& f : cmp.clusters)
      for (int e : f.elements)
        if (focus.count(e)) return true;
    return false;
  };
  CHECK_FALSE(found(without));
  CHECK(found(with));
  CHECK(with.clusters.size() == 1);
  // P2, 85, male, no focus: about 11.5 above the cohort mean, 2 spreads of the age-mixed normals:
  // every element biased upwards without the model, centred with it. Beyond the normals' ages the
  // prediction is uncertain (leverage about 0.4 here) and the spread estimated with 11 dof: the z
  // test, which takes the spread as exact, counts more |z| >= 3 than Crawford-Howell's t.
  const ElementTable p2 = subject("sub-P2", 12, 85, 'M');
  const std::vector<double> row2 = covariate_row(cov, "sub-P2", "p2");
  CompareOptions ch;
  ch.test = SingleCaseTest::crawford_howell;
  const Comparison p2_with = compare_to_reference(el, model, p2, ch, row2);
  const Comparison p2_without = compare_to_reference(el, plain, p2, ch);
  auto mean_z = [&](const Comparison& cmp) {
    double m = 0;
    for (double z : cmp.z) m += z / el.size();
    return m;
  };
  auto share_beyond_3 = [&](const Comparison& cmp) {
    double k = 0;
    for (double z : cmp.z) k += std::abs(z) >= 3;
    return k / el.size();
  };
  CHECK(mean_z(p2_without) > 1.5);
  CHECK(std::abs(mean_z(p2_with)) < 0.3);
  CHECK(share_beyond_3(p2_with) <= 0.01);
  CHECK(share_beyond_3(compare_to_reference(el, model, p2, {}, row2)) > share_beyond_3(p2_with));
}

TEST_CASE("vpm compare and calibrate --covariates --participants: recorded, checked, refused when incomplete") {
  const std::string dir = std::string(VPM_TEST_TMP) + "/cov_cli_";
  const Cohort c = cohort(dir);
  std::string list;
  for (size_t i = 0; i < c.normals.size(); ++i) {
    write_subject_table(dir + c.names[i] + ".tsv", c.normals[i]);
    list += (i ? "," : "") + dir + c.names[i] + ".tsv";
  }
  const CanonicalElements el(def());
  write_subject_table(dir + "p1.tsv", subject("sub-P1", 11, 35, 'F', planted_focus(el, 40), 5.0));
  write_subject_table(dir + "x.tsv", subject("sub-X", 13, 35, 'F'));
  const std::string vpm = VPM_BINARY, base = " --feature pet --normalisation none --normals " + list + " --quiet";
  const std::string cov = " --covariates age,sex --participants " + c.table;
  REQUIRE(test::run_status(vpm + " compare --patient " + dir + "p1.tsv" + cov + base + " -o " + dir + "out.tsv") == 0);
  const Json side = Json::parse(test::slurp(dir + "out.json"));
  const Json* rc = side.find("reference")->find("covariates");
  REQUIRE(rc);
  CHECK(rc->find("columns")->dump(-1) == "[\"age\",\"sex=M\"]");
  CHECK(rc->find("patient")->dump(-1) == "[35,0]");
  CHECK(side.find("result")->find("clusters")->size() >= 1);
  // the TSV's reference_mean is the patient's prediction, not the cohort mean
  std::ifstream tsv(dir + "out.tsv");
  std::string header, first;
  std::getline(tsv, header);
  std::getline(tsv, first);
  CHECK(header.find("\treference_mean\t") != std::string::npos);
  std::stringstream cells(first);
  std::string cell;
  for (int k = 0; k < 5; ++k) std::getline(cells, cell, '\t');  // element shell triangle patient reference_mean
  double cohort_mean = 0;
  for (const ElementTable& n : c.normals) cohort_mean += n.features[0].mean[0] / double(c.normals.size());
  CHECK(std::stod(cell) < cohort_mean - 3.0);  // 35, female: 4.5 + 1 below
  // incomplete options, a patient missing from the table
  CHECK(test::run_status(vpm + " compare --patient " + dir + "p1.tsv --covariates age" + base + " -o " + dir +
                         "bad.tsv 2> /dev/null") == 2);
  CHECK(test::run_status(vpm + " compare --patient " + dir + "x.tsv" + cov + base + " -o " + dir + "bad.tsv 2> " + dir +
                         "err.txt") == 2);
  CHECK_THAT(test::slurp(dir + "err.txt"), Catch::Contains("no row for participant 'sub-X'"));
  // a calibration with the covariates applies; one without them is refused
  REQUIRE(test::run_status(vpm + " calibrate" + cov + base + " -o " + dir + "cal.json") == 0);
  CHECK(Json::parse(test::slurp(dir + "cal.json")).find("covariates")->dump(-1) == "[\"age\",\"sex\"]");
  CHECK(test::run_status(vpm + " compare --patient " + dir + "p1.tsv --min-cluster-from " + dir + "cal.json" + cov +
                         base + " -o " + dir + "cal_out.tsv") == 0);
  CHECK(test::run_status(vpm + " compare --patient " + dir + "p1.tsv --min-cluster-from " + dir + "cal.json" + base +
                         " -o " + dir + "bad.tsv 2> " + dir + "err2.txt") == 2);
  CHECK_THAT(test::slurp(dir + "err2.txt"), Catch::Contains("calibrated with covariates"));
}
