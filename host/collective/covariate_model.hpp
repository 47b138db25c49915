#pragma once
// Private: the normative model of a reference with covariates (vpm/statistics.hpp,
// vpm/covariates.hpp): per element, least squares of the normals' values on an intercept and
// the centred covariates.
#include <vector>

#include "vpm/covariates.hpp"
#include "vpm/statistics.hpp"

namespace vpm::detail {

/// Fills ref's mean, std, count, covariates, covariate_centre, image_covariate_centre,
/// coefficients and gram_inverse from `values` (per normal, per element; NaN: no data), the
/// normals' `design` (may be empty) and `image` (per normal, per element, the image covariate's
/// values; empty when ref.image_covariate is, which the caller sets). An element needs more
/// normals with data (in both) than the model's columns q, else NaN; an element whose design is
/// singular there (the image covariate constant over the normals) is NaN too. InputError when
/// the subject design is rank-deficient over the normals (a covariate constant, or two the same).
void fit_covariate_model(const std::vector<std::vector<double>>& values, const CovariateDesign& design,
                         const std::vector<std::vector<double>>& image, Reference& ref);

/// A patient's expected value at element e from the model, the patient's design `row` and its
/// value of the image covariate there (ignored without one), and the leverage h = x^T (X^T X)^-1 x
/// of that row (x: 1, then row - centre, then image_value - its centre); NaN without a model there.
struct ModelPrediction {
  double expected, leverage;
};
ModelPrediction predict(const Reference& ref, int e, const std::vector<double>& row, double image_value);

}  // namespace vpm::detail
