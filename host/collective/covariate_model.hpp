#pragma once
// Private: the normative model of a reference with covariates (vpm/statistics.hpp,
// vpm/covariates.hpp): per element, least squares of the normals' values on an intercept and
// the centred covariates.
#include <vector>

#include "collective/reference_values.hpp"
#include "vpm/covariates.hpp"
#include "vpm/statistics.hpp"

namespace vpm::detail {

/// Fills ref's mean, std, count, covariates, covariate_centre, image_covariate_centre,
/// coefficients and gram_inverse from the normals' values `use` (NaN: no data; their image
/// covariate's values read when ref.image_covariate, which the caller sets, is not empty) and
/// their `design` (may be empty). An element needs more
/// normals with data (in both) than the model's columns q, else NaN; an element whose design is
/// singular there (the image covariate constant over the normals) is NaN too. InputError when
/// the subject design is rank-deficient over the normals (a covariate constant, or two the same).
void fit_covariate_model(const std::vector<const NormalValues*>& use, const CovariateDesign& design, Reference& ref);

/// A patient's expected value at element e from the model, the patient's design `row` and its
/// value of the image covariate there (ignored without one), and the leverage h = x^T (X^T X)^-1 x
/// of that row (x: 1, then row - centre, then image_value - its centre); NaN without a model there.
struct ModelPrediction {
  double expected, leverage;
};
ModelPrediction predict(const Reference& ref, int e, const std::vector<double>& row, double image_value);

}  // namespace vpm::detail
