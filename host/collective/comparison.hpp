#pragma once
// Private: a comparison from a subject's values rather than its table (the leave-one-out
// calibration compares each normal's values, read once, with the reference of the others), and
// the recipe a reference was built with.
#include <string>
#include <vector>

#include "vpm/covariates.hpp"
#include "vpm/reference_sums.hpp"
#include "vpm/statistics.hpp"

namespace vpm::detail {

/// The recipe of `ref` (what its normals' values were read with).
ReferenceRecipe recipe_of(const Reference& ref);

/// compare_to_reference of a subject whose values (normal_values with recipe_of(ref)) are given;
/// `who` names it in messages.
Comparison compare_values(const CanonicalElements& el, const Reference& ref, const NormalValues& values,
                          const CompareOptions& options, const std::vector<double>& covariates, const std::string& who);

}  // namespace vpm::detail
