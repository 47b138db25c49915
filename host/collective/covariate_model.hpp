#pragma once
// Private: a prediction of the normative model of a reference with covariates
// (vpm/statistics.hpp, vpm/covariates.hpp; fitted from the normals' sums, vpm/reference_sums.hpp).
#include <vector>

#include "vpm/covariates.hpp"
#include "vpm/statistics.hpp"

namespace vpm::detail {

/// A patient's expected value at element e from the model, the patient's design `row` and its
/// value of the image covariate there (ignored without one), and the leverage h = x^T (X^T X)^-1 x
/// of that row (x: 1, then row - centre, then image_value - its centre); NaN without a model there.
struct ModelPrediction {
  double expected, leverage;
};
ModelPrediction predict(const Reference& ref, int e, const std::vector<double>& row, double image_value);

}  // namespace vpm::detail
