// The streaming reference (vpm/reference_sums.hpp): the reference from sums equals the one
// computed from every normal's values at once (an oracle here: per element the two-pass mean and
// spread, or least squares on the centred design), with smoothing, shrinkage, subject covariates
// and an image covariate; leaving one normal out of the totals equals summing the others; sums
// of disjoint groups merge to the sums of all; the HDF5 file round-trips exactly and refuses what
// cannot be sums; `vpm reference` + `--merge` + `vpm compare --reference` equal `vpm compare
// --normals`.
#include <catch2/catch.hpp>
#include <Eigen/Dense>
#include <cmath>
#include <fstream>
#include <random>
#include <string>

#include "support/elements.hpp"
#include "support/process.hpp"
#include "support/scratch.hpp"
#include "vpm/calibration.hpp"
#include "vpm/error.hpp"
#include "vpm/json.hpp"
#include "vpm/reference_sums.hpp"

using namespace vpm;

namespace {

// A normal: "pet" = 100 + 0.4 age + 3 [sex M] - 1.2 (t1w - 50) + noise, "t1w" ~ 50 + N(0, 5);
// element (seed % 7) and every 11th lack data.
ElementTable normal(const CanonicalElements& el, int i) {
  ElementTable t;
  t.definition = el.definition();
  t.subject = "sub-" + std::to_string(i);
  ElementFeature pet, t1w;
  pet.name = "pet";
  t1w.name = "t1w";
  std::mt19937 rng(static_cast<unsigned>(1000 + i));
  std::normal_distribution<double> g(0, 1);
  const double age = 20 + 3 * i, male = i % 2;
  for (int e = 0; e < el.size(); ++e) {
    const double s = 50 + 5 * g(rng);
    const bool gap = e == i % 7 || (e + i) % 11 == 0;
    t1w.mean.push_back(s);
    pet.mean.push_back(100 + 0.4 * age + 3 * male - 1.2 * (s - 50) + 2 * g(rng));
    pet.count.push_back(gap ? 0 : 8);
    t1w.count.push_back(8);
    pet.std.push_back(1);
    t1w.std.push_back(1);
  }
  t.features = {pet, t1w};
  return t;
}

Covariates covariates(int n) {
  Covariates c;
  c.source = "participants.tsv";
  c.names = {"age", "sex"};
  c.columns = {"age", "sex=M"};
  for (int i = 0; i < n; ++i) c.rows["sub-" + std::to_string(i)] = {20.0 + 3 * i, double(i % 2)};
  return c;
}

// The oracle: per element, least squares of the values on [1, centred covariates, centred image
// covariate] over the normals with data (q = 1: mean and sample spread), as Reference documents.
Reference oracle(const CanonicalElements& el, const std::vector<NormalValues>& v, const std::vector<std::vector<double>>& rows,
                 bool image) {
  const size_t N = v.size(), n = static_cast<size_t>(el.size()), p = rows.empty() ? 0 : rows[0].size();
  const int q = 1 + static_cast<int>(p) + (image ? 1 : 0);
  std::vector<double> centre(p, 0.0);
  for (const auto& r : rows)
    for (size_t j = 0; j < p; ++j) centre[j] += r[j] / double(N);
  Reference r;
  r.mean.assign(n, NAN);
  r.std.assign(n, NAN);
  r.count.assign(n, 0);
  r.coefficients.assign(n * q, NAN);
  for (size_t e = 0; e < n; ++e) {
    std::vector<size_t> with;
    for (size_t i = 0; i < N; ++i)
      if (!std::isnan(v[i].feature[e]) && (!image || !std::isnan(v[i].image[e]))) with.push_back(i);
    const int c = static_cast<int>(with.size());
    r.count[e] = c;
    if (c <= std::max(q, 1) || (q == 1 && c < 2)) continue;
    double im_centre = 0;
    for (size_t i : with) im_centre += image ? v[i].image[e] / c : 0;
    Eigen::MatrixXd X(c, q);
    Eigen::VectorXd y(c);
    for (int k = 0; k < c; ++k) {
      const size_t i = with[static_cast<size_t>(k)];
      X(k, 0) = 1;
      for (size_t j = 0; j < p; ++j) X(k, 1 + static_cast<Eigen::Index>(j)) = rows[i][j] - centre[j];
      if (image) X(k, q - 1) = v[i].image[e] - im_centre;
      y(k) = v[i].feature[e];
    }
    const Eigen::VectorXd beta = X.colPivHouseholderQr().solve(y);
    r.mean[e] = beta(0);
    r.std[e] = std::sqrt((y - X * beta).squaredNorm() / (c - q));
    for (int a = 0; a < q; ++a) r.coefficients[e * q + a] = beta(a);
  }
  return r;
}

void check_close(const std::vector<double>& a, const std::vector<double>& b, double tol) {
  REQUIRE(a.size() == b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(b[i])) {
      CHECK(std::isnan(a[i]));
      continue;
    }
    CHECK(a[i] == Approx(b[i]).epsilon(tol).margin(tol));
  }
}

struct Cohort {
  CanonicalElements el{test::small_elements()};
  std::vector<ElementTable> tables;
  std::vector<std::string> names;
  explicit Cohort(int n) {
    for (int i = 0; i < n; ++i) {
      tables.push_back(normal(el, i));
      names.push_back("n" + std::to_string(i) + ".h5");
    }
  }
};

ReferenceRecipe recipe(bool with_covariates, bool image, int smoothing = 0) {
  ReferenceRecipe r;
  r.feature = "pet";
  r.normalisation = Normalisation::proportional;
  r.smoothing = smoothing;
  if (image) r.image_covariate = "t1w";
  if (with_covariates) {
    r.covariates = {"age", "sex"};
    r.covariate_columns = {"age", "sex=M"};
  }
  return r;
}

// `vpm ARGS`: its exit status and what it wrote to stderr.
struct Run {
  int status;
  std::string err;
};
Run run_vpm(const std::string& args) {
  const std::string err = test::fresh_dir("reference_cli_err") + "/err.txt";
  const int status = test::run_status(std::string(VPM_BINARY) + " " + args + " --quiet 2> " + err);
  return {status, test::slurp(err)};
}

}  // namespace

// The values and design rows every test derives its expectations from.
struct Summed {
  std::vector<NormalValues> values;
  std::vector<std::vector<double>> rows;
  CovariateDesign design;
};

Summed values_of(const Cohort& c, const ReferenceRecipe& rec, const Covariates& cov, std::vector<size_t> which = {}) {
  if (which.empty())
    for (size_t i = 0; i < c.tables.size(); ++i) which.push_back(i);
  Summed s;
  if (!rec.covariates.empty()) {
    s.design.source = cov.source;
    s.design.names = cov.names;
    s.design.columns = cov.columns;
  }
  for (size_t i : which) {
    s.values.push_back(normal_values(&c.el, c.tables[i], c.names[i], rec));
    if (!rec.covariates.empty()) {
      s.rows.push_back(covariate_row(cov, c.tables[i].subject, c.names[i]));
      s.design.rows.push_back(s.rows.back());
    }
  }
  return s;
}

TEST_CASE("reference sums: the reference from sums equals the oracle, with and without models") {
  const Cohort c(12);
  const Covariates cov = covariates(12);
  for (const bool with_cov : {false, true})
    for (const bool image : {false, true})
      for (const int smoothing : {0, 1}) {
        CAPTURE(with_cov, image, smoothing);
        const ReferenceRecipe rec = recipe(with_cov, image, smoothing);
        const Summed s = values_of(c, rec, cov);
        const ReferenceSums sums = sum_normals(c.el.definition(), rec, tables_in_memory(c.tables, c.names, rec, &c.el, s.design));
        CHECK(sums.normals() == c.names);
        const Reference got = sums.reference(&c.el, 0);
        const Reference want = oracle(c.el, s.values, s.rows, image);
        CHECK(got.count == want.count);
        check_close(got.mean, want.mean, 1e-9);
        check_close(got.std, want.std, 1e-9);
        if (with_cov || image) check_close(got.coefficients, want.coefficients, 1e-8);
        // build_reference (the library's one call) is the same sums
        const Reference built = build_reference(c.el, c.tables, c.names, "pet", Normalisation::proportional, smoothing, 0,
                                                with_cov ? s.design : CovariateDesign{}, image ? "t1w" : "");
        CHECK(built.mean == got.mean);
      }
}

TEST_CASE("reference sums: leaving a normal out of the totals equals summing the others") {
  const Cohort c(9);
  const Covariates cov = covariates(9);
  for (const bool with_cov : {false, true})
    for (const bool image : {false, true}) {
      CAPTURE(with_cov, image);
      const ReferenceRecipe rec = recipe(with_cov, image);
      const Summed all = values_of(c, rec, cov);
      const ReferenceSums totals = sum_normals(c.el.definition(), rec, tables_in_memory(c.tables, c.names, rec, &c.el, all.design));
      for (size_t out : {size_t{0}, size_t{4}, size_t{8}}) {
        std::vector<size_t> others;
        for (size_t i = 0; i < c.tables.size(); ++i)
          if (i != out) others.push_back(i);
        const Summed rest = values_of(c, rec, cov, others);
        const Reference without = totals.reference_without(&c.el, 0.5, out, all.values[out]);
        ReferenceSums direct(c.el.definition(), rec);
        for (size_t k = 0; k < others.size(); ++k)
          direct.add(c.names[others[k]], rest.values[k], rest.rows.empty() ? std::vector<double>{} : rest.rows[k]);
        const Reference want = direct.reference(&c.el, 0.5);
        CHECK(without.subjects == 8);
        CHECK(without.count == want.count);
        check_close(without.mean, want.mean, 1e-10);
        check_close(without.std, want.std, 1e-10);
        check_close(without.coefficients, want.coefficients, 1e-9);
        check_close(without.gram_inverse, want.gram_inverse, 1e-9);
        CHECK(without.covariate_centre.size() == want.covariate_centre.size());
      }
    }
}

TEST_CASE("reference sums: disjoint groups merge to the sums of all, and what cannot merge is refused") {
  const Cohort c(10);
  const Covariates cov = covariates(10);
  const ReferenceRecipe rec = recipe(true, true);
  const Summed all = values_of(c, rec, cov);
  const ReferenceSums whole = sum_normals(c.el.definition(), rec, tables_in_memory(c.tables, c.names, rec, &c.el, all.design));
  ReferenceSums a(c.el.definition(), rec), b(c.el.definition(), rec);
  for (size_t i = 0; i < 10; ++i) (i < 4 ? a : b).add(c.names[i], all.values[i], all.rows[i]);
  a.merge(b);
  CHECK(a.normals() == whole.normals());
  CHECK(a.design() == whole.design());
  for (int e = 0; e < c.el.size(); ++e)
    for (int k = 0; k < whole.stride(); ++k) CHECK(a.element(e)[k] == Approx(whole.element(e)[k]).epsilon(1e-13));
  check_close(a.reference(&c.el, 0.8).mean, whole.reference(&c.el, 0.8).mean, 1e-12);
  // the same normal twice, another recipe, another definition
  CHECK_THROWS_WITH(a.merge(b), Catch::Contains("n4.h5: this normal is in both sums"));
  CHECK_THROWS_WITH(a.add(c.names[0], all.values[0], all.rows[0]), Catch::Contains("in the reference already"));
  ReferenceSums other(c.el.definition(), recipe(true, false));
  CHECK_THROWS_WITH(a.merge(other), Catch::Contains("the recipes differ"));
  ElementDefinition d = c.el.definition();
  d.samples = 4;
  CHECK_THROWS_WITH(a.merge(ReferenceSums(d, rec)), Catch::Contains("the element definitions differ"));
  CHECK(recipe_difference(rec, recipe(true, false)) == std::optional<std::string>("image covariate (none), not t1w"));
}

TEST_CASE("reference sums: the HDF5 file round-trips exactly and refuses what cannot be sums") {
  const Cohort c(6);
  const Covariates cov = covariates(6);
  const ReferenceRecipe rec = recipe(true, false);
  const Summed all = values_of(c, rec, cov);
  const ReferenceSums sums = sum_normals(c.el.definition(), rec, tables_in_memory(c.tables, c.names, rec, &c.el, all.design));
  const std::string dir = test::fresh_dir("reference_sums");
  write_reference_sums(dir + "/sums.h5", sums);
  const ReferenceSums back = read_reference_sums(dir + "/sums.h5");
  CHECK(back.normals() == sums.normals());
  CHECK(back.design() == sums.design());
  CHECK(back.recipe() == sums.recipe());
  CHECK(back.definition() == sums.definition());
  for (int e = 0; e < c.el.size(); ++e)
    for (int k = 0; k < sums.stride(); ++k) REQUIRE(back.element(e)[k] == sums.element(e)[k]);
  // truncated, not HDF5, a table instead of sums, missing
  std::ifstream in(dir + "/sums.h5", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir + "/cut.h5", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  CHECK_THROWS_AS(read_reference_sums(dir + "/cut.h5"), InputError);
  CHECK_THROWS_WITH(read_reference_sums(dir + "/cut.h5"), Catch::Contains("cut.h5"));
  std::ofstream(dir + "/text.h5") << "element\tshell\n";
  CHECK_THROWS_WITH(read_reference_sums(dir + "/text.h5"), Catch::Contains("text.h5: not an HDF5 file"));
  write_subject_table(dir + "/table.h5", c.tables[0]);
  CHECK_THROWS_WITH(read_reference_sums(dir + "/table.h5"), Catch::Contains("not vpm reference sums"));
  CHECK_THROWS_WITH(read_reference_sums(dir + "/none.h5"), Catch::Contains("none.h5: no such file"));
}

TEST_CASE("reference sums: vpm reference, --merge and vpm compare --reference give vpm compare --normals' result") {
  const Cohort c(8);
  const std::string dir = test::fresh_dir("reference_cli");
  std::string all, first, second;
  for (size_t i = 0; i < c.tables.size(); ++i) {
    const std::string path = dir + "/" + c.names[i];
    write_subject_table(path, c.tables[i]);
    all += (all.empty() ? "" : ",") + path;
    (i < 5 ? first : second) += ((i < 5 ? first : second).empty() ? "" : ",") + path;
  }
  std::ofstream(dir + "/list.txt") << [&] {
    std::string l;
    for (const std::string& n : c.names) l += dir + "/" + n + "\n";
    return l;
  }();
  const std::string opts = " --feature pet --image-covariate t1w --smooth 1";
  REQUIRE(run_vpm("reference --normals " + first + opts + " -o " + dir + "/a.h5").status == 0);
  REQUIRE(run_vpm("reference --normals " + second + opts + " -o " + dir + "/b.h5").status == 0);
  REQUIRE(run_vpm("reference --merge " + dir + "/a.h5," + dir + "/b.h5 -o " + dir + "/all.h5").status == 0);
  const std::string patient = " --patient " + dir + "/n0.h5 --shrink 0.5 --threshold 2";
  REQUIRE(run_vpm("compare --normals @" + dir + "/list.txt" + opts + patient + " -o " + dir + "/direct.tsv").status == 0);
  REQUIRE(run_vpm("compare --reference " + dir + "/all.h5" + opts + patient + " -o " + dir + "/merged.tsv").status == 0);
  const Json direct = read_json_file(dir + "/direct.json"), merged = read_json_file(dir + "/merged.json");
  CHECK(merged.find("result")->dump() == direct.find("result")->dump());
  CHECK(merged.find("reference")->find("tables")->size() == 8);
  // a reference summed with another recipe is refused, naming the difference
  const auto bad = run_vpm("compare --reference " + dir + "/all.h5 --feature pet --smooth 1" + patient + " -o " + dir + "/bad.tsv");
  CHECK(bad.status == 2);
  CHECK_THAT(bad.err, Catch::Contains("was summed with image covariate t1w, not (none)"));
  CHECK(run_vpm("reference --merge " + dir + "/a.h5," + dir + "/a.h5 -o " + dir + "/twice.h5").status == 2);
}
