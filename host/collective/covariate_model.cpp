// The normative model of a reference with covariates (collective/covariate_model.hpp).
#include "collective/covariate_model.hpp"

#include <cmath>

namespace vpm::detail {

ModelPrediction predict(const Reference& ref, int e, const std::vector<double>& row, double image_value) {
  const size_t q = static_cast<size_t>(ref.model_columns()), p = ref.covariates.size();
  const double* beta = ref.coefficients.data() + static_cast<size_t>(e) * q;
  const double* Gi = ref.gram_inverse.data() + static_cast<size_t>(e) * q * q;
  double small[16];
  std::vector<double> large(q > 16 ? q : 0);  // references of more columns than sums make (built by hand)
  double* x = q > 16 ? large.data() : small;
  x[0] = 1.0;
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
