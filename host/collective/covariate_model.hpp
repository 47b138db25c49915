#pragma once
// Private: the normative model of a reference with covariates (vpm/statistics.hpp,
// vpm/covariates.hpp): per element, least squares of the normals' values on an intercept and
// the centred covariates.
#include <vector>

#include "vpm/covariates.hpp"
#include "vpm/statistics.hpp"

namespace vpm::detail {

/// Fills ref's mean, std, count, covariates, covariate_centre, coefficients and gram_inverse from
/// `values` (per normal, per element; NaN: no data) and the normals' `design`. An element needs
/// more normals with data than p + 1 (p: the design's columns), else NaN. InputError when the
/// design is rank-deficient over the normals (a covariate constant, or two the same).
void fit_covariate_model(const std::vector<std::vector<double>>& values, const CovariateDesign& design, Reference& ref);

/// A patient's expected value at element e from the model and the patient's design `row`, and
/// the leverage h = x^T (X^T X)^-1 x of that row (x: 1, then row - centre); NaN without a model there.
struct ModelPrediction {
  double expected, leverage;
};
ModelPrediction predict(const Reference& ref, int e, const std::vector<double>& row);

}  // namespace vpm::detail
