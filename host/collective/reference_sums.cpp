// The streaming reference (vpm/reference_sums.hpp): sums that add and merge, and the reference
// fitted from them.
#include "vpm/reference_sums.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <set>

#include "core/parallel.hpp"
#include "vpm/error.hpp"

namespace vpm {

namespace {

constexpr int kMaxColumns = 16;

// The design row x (q values) of a normal at one element: 1, its covariates, its image covariate there.
inline void design_x(const std::vector<double>& row, bool image, double image_value, int q, double* x) {
  x[0] = 1.0;
  for (size_t j = 0; j < row.size(); ++j) x[1 + j] = row[j];
  if (image) x[q - 1] = image_value;
}

// Reference::shrinkage: each variance pulled towards the mean over the element and its neighbours.
void shrink_spread(const CanonicalElements& el, double shrinkage, std::vector<double>& std) {
  std::vector<double> var(std.size());
  for (size_t e = 0; e < std.size(); ++e) var[e] = std[e] * std[e];
  const CanonicalElements::Adjacency& adjacency = el.adjacency();
  detail::parallel_for(static_cast<int>(std.size()), 65536, [&](int begin, int end) {
    for (int e = begin; e < end; ++e) {
      if (std::isnan(var[static_cast<size_t>(e)])) continue;
      double sum = var[static_cast<size_t>(e)];
      int k = 1;
      for (int nb : adjacency.of(e))
        if (!std::isnan(var[static_cast<size_t>(nb)])) {
          sum += var[static_cast<size_t>(nb)];
          ++k;
        }
      std[static_cast<size_t>(e)] = std::sqrt((1 - shrinkage) * var[static_cast<size_t>(e)] + shrinkage * sum / k);
    }
  });
}

// InputError unless the centred subject design X (intercept first) has full column rank.
void check_rank(const Eigen::MatrixXd& X, const ReferenceRecipe& r) {
  Eigen::FullPivLU<Eigen::MatrixXd> lu(X);
  lu.setThreshold(1e-10);
  if (lu.rank() == X.cols()) return;
  std::string cols;
  for (const std::string& c : r.covariate_columns) cols += (cols.empty() ? "" : ", ") + c;
  throw InputError("reference: the covariates (" + cols + ") do not vary independently over the " +
                   std::to_string(X.rows()) + " normals (one is constant, or follows from the others)");
}

// What every element's fit shares: the model's shape and the subject covariates' centre.
struct FitShape {
  int q = 1, p = 0;
  bool image = false;
  std::vector<double> centre;  // p values
};

// The packed terms of one normal at one element, times `sign` (+1 adds, -1 takes out): x x^T's
// upper triangle, x y, y^2 (Q: the model's columns when fixed at compile time, else q).
template <int Q>
inline void accumulate(double* s, int q, const double* x, double y, double sign) {
  const int n = Q > 0 ? Q : q;
  int k = 0;
  for (int a = 0; a < n; ++a)
    for (int b = a; b < n; ++b) s[k++] += sign * (x[a] * x[b]);
  for (int a = 0; a < n; ++a) s[k++] += sign * (x[a] * y);
  s[k] += sign * (y * y);
}

void accumulate_any(double* s, int q, const double* x, double y, double sign) {
  switch (q) {
    case 1: return accumulate<1>(s, q, x, y, sign);
    case 2: return accumulate<2>(s, q, x, y, sign);
    case 3: return accumulate<3>(s, q, x, y, sign);
    case 4: return accumulate<4>(s, q, x, y, sign);
    default: return accumulate<0>(s, q, x, y, sign);
  }
}

// One element's model fit (q > 1 columns) from its sums `s` into r at e; Q as accumulate's.
template <int Q>
void fit_model(const double* s, const FitShape& f, size_t e, Reference& r) {
  constexpr int M = Q > 0 ? Q : kMaxColumns, R = Q > 0 ? Q : int(Eigen::Dynamic);
  using MatQ = Eigen::Matrix<double, R, R, 0, M, M>;
  using VecQ = Eigen::Matrix<double, R, 1, 0, M, 1>;
  const int q = Q > 0 ? Q : f.q, P = q * (q + 1) / 2;
  const double n = s[0];
  MatQ G(q, q);
  for (int a = 0, k = 0; a < q; ++a)
    for (int b = a; b < q; ++b, ++k) G(a, b) = G(b, a) = s[k];
  VecQ bv(q), x0 = VecQ::Zero(q);
  for (int a = 0; a < q; ++a) bv(a) = s[P + a];
  const double yy = s[P + q];
  for (int j = 0; j < f.p; ++j) x0(1 + j) = f.centre[static_cast<size_t>(j)];
  if (f.image) x0(q - 1) = G(0, q - 1) / n;
  // centred: x_c = x - x0 (the intercept column stays 1), y taken about its mean
  const VecQ g = G.col(0);
  const MatQ Gc = G - x0 * g.transpose() - g * x0.transpose() + n * x0 * x0.transpose();
  const double ybar = bv(0) / n;
  const VecQ bc = bv - x0 * bv(0) - ybar * Gc.col(0);
  const double yyc = yy - bv(0) * ybar;
  Eigen::LDLT<MatQ> ldlt(Gc);
  if (ldlt.info() != Eigen::Success || ldlt.vectorD().minCoeff() <= 1e-12 * ldlt.vectorD().maxCoeff()) return;
  VecQ beta = ldlt.solve(bc);
  const double rss = std::max(0.0, yyc - beta.dot(bc));
  beta(0) += ybar;
  const MatQ Gi = ldlt.solve(MatQ::Identity(q, q));
  r.mean[e] = beta(0);
  r.std[e] = std::sqrt(rss / (n - q));
  if (f.image) r.image_covariate_centre[e] = x0(q - 1);
  const size_t uq = static_cast<size_t>(q);
  for (int a = 0; a < q; ++a) {
    r.coefficients[e * uq + static_cast<size_t>(a)] = beta(a);
    for (int b = 0; b < q; ++b) r.gram_inverse[(e * uq + static_cast<size_t>(a)) * uq + static_cast<size_t>(b)] = Gi(a, b);
  }
}

// fit_model<2> written out: one covariate (the image covariate, the workflow's default, or one
// subject covariate), the same arithmetic without the general solver (7x faster).
void fit_line(const double* s, const FitShape& f, size_t e, Reference& r) {
  const double n = s[0], g1 = s[1], g11 = s[2], b0 = s[3], b1 = s[4], yy = s[5];
  const double c = f.image ? g1 / n : f.centre[0];
  // centred design (1, x - c): G_c = [[n, g1 - n c], [., g11 - 2 c g1 + n c^2]]
  const double a01 = g1 - n * c, a11 = g11 - 2 * c * g1 + n * c * c;
  const double ybar = b0 / n;
  const double c0 = b0 - ybar * n, c1 = (b1 - c * b0) - ybar * a01;  // centred x^T (y - ybar)
  const double yyc = yy - b0 * ybar;
  // singular as fit_model's LDLT judges it: the pivots (the larger diagonal, then det / it)
  const double det = n * a11 - a01 * a01, pivot = std::max(n, a11), second = det / pivot;
  if (!(std::min(pivot, second) > 1e-12 * std::max(pivot, second))) return;
  const double i00 = a11 / det, i01 = -a01 / det, i11 = n / det;
  const double beta0 = i00 * c0 + i01 * c1, beta1 = i01 * c0 + i11 * c1;
  const double rss = std::max(0.0, yyc - (beta0 * c0 + beta1 * c1));
  r.mean[e] = beta0 + ybar;
  r.std[e] = std::sqrt(rss / (n - 2));
  if (f.image) r.image_covariate_centre[e] = c;
  r.coefficients[2 * e] = beta0 + ybar;
  r.coefficients[2 * e + 1] = beta1;
  double* gi = r.gram_inverse.data() + 4 * e;
  gi[0] = i00, gi[1] = i01, gi[2] = i01, gi[3] = i11;
}

// One element's fit from its sums `s` (packed sum x x^T, sum x y, sum y^2) into r at e.
void fit_element(const double* s, const FitShape& f, int e, Reference& r) {
  const size_t ue = static_cast<size_t>(e);
  const double n = s[0];
  r.count[ue] = static_cast<int>(std::lround(n));
  if (f.q == 1) {  // no model: the normals' mean and sample standard deviation
    if (r.count[ue] < 2) return;
    const double mean = s[1] / n;
    r.mean[ue] = mean;
    r.std[ue] = std::sqrt(std::max(0.0, s[2] - s[1] * mean) / (n - 1));
    return;
  }
  if (r.count[ue] <= f.q) return;
  switch (f.q) {
    case 2: return fit_line(s, f, ue, r);
    case 3: return fit_model<3>(s, f, ue, r);
    case 4: return fit_model<4>(s, f, ue, r);
    default: return fit_model<0>(s, f, ue, r);
  }
}

}  // namespace

// ---- the recipe ------------------------------------------------------------------------

namespace {

ReferenceRecipe make_recipe(const std::string& feature, Normalisation normalisation, int smoothing,
                            const std::string& image_covariate, const std::string* source,
                            const std::vector<std::string>* names, const std::vector<std::string>* columns) {
  ReferenceRecipe r;
  r.feature = feature;
  r.normalisation = normalisation;
  r.smoothing = smoothing;
  r.image_covariate = image_covariate;
  if (source) r.covariate_table = *source, r.covariates = *names, r.covariate_columns = *columns;
  return r;
}

}  // namespace

ReferenceRecipe reference_recipe(const std::string& feature, Normalisation normalisation, int smoothing,
                                 const std::string& image_covariate, const Covariates* c) {
  if (!c) return make_recipe(feature, normalisation, smoothing, image_covariate, nullptr, nullptr, nullptr);
  return make_recipe(feature, normalisation, smoothing, image_covariate, &c->source, &c->names, &c->columns);
}

ReferenceRecipe reference_recipe(const std::string& feature, Normalisation normalisation, int smoothing,
                                 const std::string& image_covariate, const CovariateDesign& d) {
  return make_recipe(feature, normalisation, smoothing, image_covariate, &d.source, &d.names, &d.columns);
}

int ReferenceRecipe::model_columns() const {
  return 1 + static_cast<int>(covariate_columns.size()) + (image_covariate.empty() ? 0 : 1);
}

bool ReferenceRecipe::operator==(const ReferenceRecipe& o) const {
  return feature == o.feature && normalisation == o.normalisation && smoothing == o.smoothing &&
         image_covariate == o.image_covariate && covariates == o.covariates && covariate_columns == o.covariate_columns;
}

std::optional<std::string> recipe_difference(const ReferenceRecipe& wanted, const ReferenceRecipe& made) {
  auto shown = [](const std::string& s) { return s.empty() ? std::string("(none)") : s; };
  auto join = [](const std::vector<std::string>& v) {
    std::string t;
    for (const std::string& x : v) t += (t.empty() ? "" : ",") + x;
    return t;
  };
  auto differ = [&](const std::string& what, const std::string& m, const std::string& w) {
    return what + " " + shown(m) + ", not " + shown(w);
  };
  if (made.feature != wanted.feature) return differ("feature", made.feature, wanted.feature);
  if (made.normalisation != wanted.normalisation)
    return differ("normalisation", to_string(made.normalisation), to_string(wanted.normalisation));
  if (made.smoothing != wanted.smoothing)
    return differ("smoothing", std::to_string(made.smoothing), std::to_string(wanted.smoothing));
  if (made.image_covariate != wanted.image_covariate)
    return differ("image covariate", made.image_covariate, wanted.image_covariate);
  if (made.covariates != wanted.covariates) return differ("covariates", join(made.covariates), join(wanted.covariates));
  if (made.covariate_columns != wanted.covariate_columns)
    return differ("covariate columns", join(made.covariate_columns), join(wanted.covariate_columns));
  return std::nullopt;
}

Json to_json(const ReferenceRecipe& r) {
  Json j = Json::object();
  j["feature"] = r.feature;
  j["normalisation"] = to_string(r.normalisation);
  j["smoothing"] = r.smoothing;
  j["image_covariate"] = r.image_covariate;
  Json c = Json::array(), cc = Json::array();
  for (const std::string& s : r.covariates) c.push_back(s);
  for (const std::string& s : r.covariate_columns) cc.push_back(s);
  j["covariates"] = c;
  j["covariate_columns"] = cc;
  j["covariate_table"] = r.covariate_table;
  return j;
}

// ---- the sums ------------------------------------------------------------------------------

ReferenceSums::ReferenceSums(const ElementDefinition& definition, ReferenceRecipe recipe)
    : definition_(definition), recipe_(std::move(recipe)) {
  if (recipe_.smoothing < 0 || recipe_.smoothing > 8)
    throw InputError("reference: smoothing " + std::to_string(recipe_.smoothing) + " is not in 0..8");
  if (recipe_.feature.empty()) throw InputError("reference: no feature named");
  if (recipe_.image_covariate == recipe_.feature)
    throw InputError("reference: the image covariate '" + recipe_.feature + "' is the feature compared itself");
  q_ = recipe_.model_columns();
  if (q_ > kMaxColumns)
    throw InputError("reference: a model of " + std::to_string(q_) + " columns (at most " + std::to_string(kMaxColumns) +
                     ": fewer covariates, or fewer levels of a categorical one)");
  stride_ = q_ * (q_ + 1) / 2 + q_ + 1;
  sums_.assign(static_cast<size_t>(definition_.elements()) * static_cast<size_t>(stride_), 0.0);
}

void ReferenceSums::add(const std::string& name, const NormalValues& v, const std::vector<double>& row) {
  const size_t n = static_cast<size_t>(definition_.elements());
  const bool image = !recipe_.image_covariate.empty();
  if (v.feature.size() != n || (image && v.image.size() != n))
    throw InputError(name + ": " + std::to_string(v.feature.size()) + " values for the " + std::to_string(n) +
                     " elements of the reference");
  if (row.size() != recipe_.covariate_columns.size())
    throw InputError(name + ": " + std::to_string(row.size()) + " covariate values for a model of " +
                     std::to_string(recipe_.covariate_columns.size()));
  for (double x : row)
    if (!std::isfinite(x)) throw InputError(name + ": a covariate value is missing");
  if (std::find(names_.begin(), names_.end(), name) != names_.end())
    throw InputError(name + ": this normal is in the reference already");
  const int q = q_;
  detail::parallel_for(static_cast<int>(n), 65536, [&](int begin, int end) {
    double x[kMaxColumns];
    design_x(row, false, 0.0, q, x);
    for (int e = begin; e < end; ++e) {
      const double y = v.feature[static_cast<size_t>(e)];
      const double im = image ? v.image[static_cast<size_t>(e)] : 0.0;
      if (std::isnan(y) || std::isnan(im)) continue;
      if (image) x[q - 1] = im;
      accumulate_any(sums_.data() + static_cast<size_t>(e) * static_cast<size_t>(stride_), q, x, y, 1.0);
    }
  });
  names_.push_back(name);
  design_.push_back(row);
}

void ReferenceSums::merge(const ReferenceSums& o) {
  if (o.definition_ != definition_)
    throw InputError("reference: the element definitions differ (" + to_string(o.definition_) + " vs " +
                     to_string(definition_) + ")");
  if (!(o.recipe_ == recipe_))
    throw InputError("reference: the recipes differ (" + to_json(o.recipe_).dump(-1) + " vs " + to_json(recipe_).dump(-1) + ")");
  const std::set<std::string> mine(names_.begin(), names_.end());
  for (const std::string& name : o.names_)
    if (mine.count(name)) throw InputError(name + ": this normal is in both sums");
  detail::parallel_for(static_cast<int>(sums_.size() / 1024 + 1), 64, [&](int begin, int end) {
    const size_t b = static_cast<size_t>(begin) * 1024, e = std::min(sums_.size(), static_cast<size_t>(end) * 1024);
    for (size_t i = b; i < e; ++i) sums_[i] += o.sums_[i];
  });
  names_.insert(names_.end(), o.names_.begin(), o.names_.end());
  design_.insert(design_.end(), o.design_.begin(), o.design_.end());
}

Reference ReferenceSums::reference(const CanonicalElements* el, double shrinkage) const {
  return fit(el, shrinkage, nullptr, nullptr);
}

Reference ReferenceSums::reference_without(const CanonicalElements* el, double shrinkage, size_t index,
                                           const NormalValues& values) const {
  if (index >= names_.size()) throw InputError("reference: no normal " + std::to_string(index) + " to leave out");
  const size_t n = static_cast<size_t>(definition_.elements());
  if (values.feature.size() != n || (!recipe_.image_covariate.empty() && values.image.size() != n))
    throw InputError(names_[index] + ": its values do not match the reference's elements");
  return fit(el, shrinkage, &design_[index], &values);
}

Reference ReferenceSums::fit(const CanonicalElements* el, double shrinkage, const std::vector<double>* out_row,
                             const NormalValues* out) const {
  if (!(shrinkage >= 0 && shrinkage <= 1))
    throw InputError("reference: shrinkage " + std::to_string(shrinkage) + " is not in [0, 1]");
  if (shrinkage > 0 && (!el || el->definition() != definition_))
    throw InputError("reference: the elements to shrink over differ from the tables' definition");
  const size_t normals = names_.size() - (out ? 1 : 0);
  if (normals < 3) throw InputError("reference: needs at least 3 normals, got " + std::to_string(normals));
  Reference r;
  r.definition = definition_;
  r.feature = recipe_.feature;
  r.normalisation = recipe_.normalisation;
  r.smoothing = recipe_.smoothing;
  r.shrinkage = shrinkage;
  r.image_covariate = recipe_.image_covariate;
  r.covariates = recipe_.covariate_columns;
  r.covariate_names = recipe_.covariates;
  r.covariate_table = recipe_.covariate_table;
  r.subjects = static_cast<int>(normals);
  FitShape f;
  f.q = q_;
  f.p = static_cast<int>(recipe_.covariate_columns.size());
  f.image = !recipe_.image_covariate.empty();
  if (f.p > 0) {  // the subject covariates' centre over the normals in, and their rank there
    f.centre.assign(static_cast<size_t>(f.p), 0.0);
    for (size_t i = 0; i < design_.size(); ++i)
      if (!out_row || &design_[i] != out_row)
        for (int j = 0; j < f.p; ++j) f.centre[static_cast<size_t>(j)] += design_[i][static_cast<size_t>(j)] / double(normals);
    Eigen::MatrixXd X(static_cast<Eigen::Index>(normals), f.p + 1);
    Eigen::Index k = 0;
    for (size_t i = 0; i < design_.size(); ++i)
      if (!out_row || &design_[i] != out_row) {
        X(k, 0) = 1.0;
        for (int j = 0; j < f.p; ++j) X(k, 1 + j) = design_[i][static_cast<size_t>(j)] - f.centre[static_cast<size_t>(j)];
        ++k;
      }
    check_rank(X, recipe_);
    r.covariate_centre = f.centre;
  }
  const size_t n = static_cast<size_t>(definition_.elements());
  const double kNaN = std::numeric_limits<double>::quiet_NaN();
  r.mean.assign(n, kNaN);
  r.std.assign(n, kNaN);
  r.count.assign(n, 0);
  if (q_ > 1) {
    r.image_covariate_centre.assign(f.image ? n : 0, kNaN);
    r.coefficients.assign(n * static_cast<size_t>(q_), kNaN);
    r.gram_inverse.assign(n * static_cast<size_t>(q_ * q_), kNaN);
  }
  detail::parallel_for(static_cast<int>(n), 65536, [&](int begin, int end) {
    std::vector<double> local(static_cast<size_t>(stride_));
    double x[kMaxColumns];
    if (out) design_x(*out_row, false, 0.0, q_, x);
    for (int e = begin; e < end; ++e) {
      const double* s = element(e);
      if (out) {  // the totals minus the normal left out, where it has data
        const double y = out->feature[static_cast<size_t>(e)];
        const double im = f.image ? out->image[static_cast<size_t>(e)] : 0.0;
        std::copy(s, s + stride_, local.begin());
        if (!std::isnan(y) && !std::isnan(im)) {
          if (f.image) x[q_ - 1] = im;
          accumulate_any(local.data(), q_, x, y, -1.0);
        }
        s = local.data();
      }
      fit_element(s, f, e, r);
    }
  });
  if (shrinkage > 0) shrink_spread(*el, shrinkage, r.std);
  return r;
}

}  // namespace vpm
