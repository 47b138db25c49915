// The normative model of a reference with covariates (collective/covariate_model.hpp).
#include "collective/covariate_model.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The normals' centred design with the intercept first: X(i, 0) = 1, X(i, 1 + j) = row_ij - centre_j.
Eigen::MatrixXd centred_design(const CovariateDesign& d, std::vector<double>& centre) {
  const Eigen::Index n = static_cast<Eigen::Index>(d.rows.size()), p = static_cast<Eigen::Index>(d.columns.size());
  centre.assign(static_cast<size_t>(p), 0.0);
  for (const auto& row : d.rows)
    for (Eigen::Index j = 0; j < p; ++j) centre[static_cast<size_t>(j)] += row[static_cast<size_t>(j)] / double(n);
  Eigen::MatrixXd X(n, p + 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    X(i, 0) = 1.0;
    for (Eigen::Index j = 0; j < p; ++j)
      X(i, 1 + j) = d.rows[static_cast<size_t>(i)][static_cast<size_t>(j)] - centre[static_cast<size_t>(j)];
  }
  return X;
}

// InputError unless X has full column rank (relative to its scale).
void check_rank(const Eigen::MatrixXd& X, const CovariateDesign& d) {
  Eigen::FullPivLU<Eigen::MatrixXd> lu(X);
  lu.setThreshold(1e-10);
  if (lu.rank() == X.cols()) return;
  std::string cols;
  for (const std::string& c : d.columns) cols += (cols.empty() ? "" : ", ") + c;
  throw InputError("reference: the covariates (" + cols + ") do not vary independently over the " +
                   std::to_string(X.rows()) + " normals (one is constant, or follows from the others)");
}

}  // namespace

void fit_covariate_model(const std::vector<const NormalValues*>& use, const CovariateDesign& design, Reference& ref) {
  const size_t n = use[0]->feature.size(), normals = use.size();
  if (!design.empty() && design.rows.size() != normals)
    throw InputError("reference: " + std::to_string(design.rows.size()) + " covariate rows for " +
                     std::to_string(normals) + " normals");
  const bool with_image = !ref.image_covariate.empty();
  Eigen::MatrixXd X = Eigen::MatrixXd::Ones(static_cast<Eigen::Index>(normals), 1);
  ref.covariate_centre.clear();
  if (!design.empty()) {
    X = centred_design(design, ref.covariate_centre);
    check_rank(X, design);
  }
  const int shared = static_cast<int>(X.cols()), q = shared + (with_image ? 1 : 0);
  ref.covariates = design.columns;
  ref.covariate_table = design.source;
  ref.covariate_names = design.names;
  ref.mean.assign(n, kNaN);
  ref.std.assign(n, kNaN);
  ref.count.assign(n, 0);
  ref.image_covariate_centre.assign(with_image ? n : 0, kNaN);
  ref.coefficients.assign(n * q, kNaN);
  ref.gram_inverse.assign(n * q * q, kNaN);
  std::vector<Eigen::Index> with;
  for (size_t e = 0; e < n; ++e) {
    with.clear();
    double centre = 0;
    for (size_t i = 0; i < normals; ++i)
      if (!std::isnan(use[i]->feature[e]) && (!with_image || !std::isnan(use[i]->image[e]))) {
        with.push_back(static_cast<Eigen::Index>(i));
        if (with_image) centre += use[i]->image[e];
      }
    const int c = static_cast<int>(with.size());
    ref.count[e] = c;
    if (c <= q) continue;
    Eigen::MatrixXd Xe(c, q);
    Eigen::VectorXd y(c);
    if (with_image) ref.image_covariate_centre[e] = centre /= c;
    for (int k = 0; k < c; ++k) {
      const size_t i = static_cast<size_t>(with[static_cast<size_t>(k)]);
      Xe.row(k).head(shared) = X.row(static_cast<Eigen::Index>(i));
      if (with_image) Xe(k, shared) = use[i]->image[e] - centre;
      y(k) = use[i]->feature[e];
    }
    const Eigen::MatrixXd G = Xe.transpose() * Xe;
    Eigen::LDLT<Eigen::MatrixXd> ldlt(G);
    if (ldlt.info() != Eigen::Success || ldlt.vectorD().minCoeff() <= 1e-12 * ldlt.vectorD().maxCoeff()) continue;
    const Eigen::VectorXd beta = ldlt.solve(Xe.transpose() * y);
    const Eigen::MatrixXd Gi = ldlt.solve(Eigen::MatrixXd::Identity(q, q));
    const double rss = (y - Xe * beta).squaredNorm();
    ref.mean[e] = beta(0);
    ref.std[e] = std::sqrt(rss / (c - q));
    for (int a = 0; a < q; ++a) {
      ref.coefficients[e * q + a] = beta(a);
      for (int b = 0; b < q; ++b) ref.gram_inverse[(e * q + a) * q + b] = Gi(a, b);
    }
  }
}

ModelPrediction predict(const Reference& ref, int e, const std::vector<double>& row, double image_value) {
  const size_t q = static_cast<size_t>(ref.model_columns()), p = ref.covariates.size();
  const double* beta = ref.coefficients.data() + static_cast<size_t>(e) * q;
  const double* Gi = ref.gram_inverse.data() + static_cast<size_t>(e) * q * q;
  std::vector<double> x(q, 1.0);
  for (size_t j = 0; j < p; ++j) x[1 + j] = row[j] - ref.covariate_centre[j];
  if (q > p + 1) x[p + 1] = image_value - ref.image_covariate_centre[static_cast<size_t>(e)];
  ModelPrediction pr{0.0, 0.0};
  for (size_t a = 0; a < q; ++a) {
    pr.expected += beta[a] * x[a];
    for (size_t b = 0; b < q; ++b) pr.leverage += x[a] * Gi[a * q + b] * x[b];
  }
  return pr;
}

}  // namespace vpm::detail
