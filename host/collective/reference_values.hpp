#pragma once
// Private: a reference (vpm/statistics.hpp) built from its normals' values rather than their
// tables. build_reference reads each table once; a leave-one-normal-out pass
// (vpm/calibration.hpp) reads every normal once and builds all its references from those shared
// values, instead of copying the other normals' tables for each one left out.
#include <string>
#include <vector>

#include "vpm/covariates.hpp"
#include "vpm/elements.hpp"
#include "vpm/statistics.hpp"

namespace vpm::detail {

/// What a reference reads from each normal and how (build_reference's arguments).
struct ReferenceRecipe {
  std::string feature;
  Normalisation normalisation = Normalisation::proportional;
  int smoothing = 0;     ///< rings (smooth_over_elements)
  double shrinkage = 0;  ///< Reference::shrinkage
  std::string image_covariate;
};

/// One normal as a reference reads it, per element: the normalised feature and the normalised
/// image covariate (empty without one), each smoothed over the recipe's rings (NaN: no data).
struct NormalValues {
  std::vector<double> feature, image;
};

/// Every normal's values. `el` (null when the recipe neither smooths nor shrinks) must have the
/// tables' definition. InputError as build_reference: smoothing < 0, shrinkage outside [0, 1],
/// fewer than 3 normals, the definitions
/// differ, a table lacks a feature, the image covariate is the feature itself.
std::vector<NormalValues> normal_values(const CanonicalElements* el, const std::vector<ElementTable>& normals,
                                        const std::vector<std::string>& names, const ReferenceRecipe& recipe);

/// Pointers to each of `values`, in order (reference_from_values' `use` for all of them).
std::vector<const NormalValues*> every_normal(const std::vector<NormalValues>& values);

/// The reference of the normals `use` (at least 3, from normal_values with the same recipe and
/// `el`, of tables with `definition`); `design` has one row per normal in `use` (or is empty).
Reference reference_from_values(const CanonicalElements* el, const ElementDefinition& definition,
                                const std::vector<const NormalValues*>& use, const ReferenceRecipe& recipe,
                                const CovariateDesign& design);

}  // namespace vpm::detail
