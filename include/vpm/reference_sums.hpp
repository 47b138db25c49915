#pragma once
// The normals' reference built in one streaming pass (paper 6.2 at the scale of cohorts;
// docs/collective.md, "A reference that streams"). Each normal adds its values to per-element
// sufficient statistics: for the design row x = (1, the subject's covariates, the element's image
// covariate) and the value y, the sums of x x^T, x y and y^2 over the normals with data there.
// The reference (vpm/statistics.hpp) follows from the sums alone, so memory is O(elements)
// whatever the number of normals; sums of disjoint groups of normals merge by addition (a cluster
// builds a reference as a map-reduce: `vpm reference` per group, then `vpm reference --merge`);
// and a reference without one normal is the totals minus that normal's terms (the leave-one-out
// calibration, vpm/calibration.hpp, never rebuilds).
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "vpm/covariates.hpp"
#include "vpm/elements.hpp"
#include "vpm/sampling.hpp"
#include "vpm/statistics.hpp"

namespace vpm {

/// What a reference sums from each normal; fixed when the sums start, and what sums must share
/// to merge and a comparison to use them.
struct ReferenceRecipe {
  std::string feature;
  Normalisation normalisation = Normalisation::proportional;
  int smoothing = 0;  ///< rings of smooth_over_elements applied to every normal's values (0..8)
  std::string image_covariate;  ///< Reference::image_covariate (empty: none)
  /// The subject covariates of the model (empty: none): Covariates::names, ::columns, ::source.
  std::vector<std::string> covariates, covariate_columns;
  std::string covariate_table;
  /// The model's columns per element: 1 + covariate_columns + (an image covariate ? 1 : 0).
  int model_columns() const;
  bool operator==(const ReferenceRecipe& o) const;
};

/// The recipe of `feature` read with `normalisation` and `smoothing`, with `image_covariate`
/// (empty: none) and the subject covariates of `covariates` (null: none).
ReferenceRecipe reference_recipe(const std::string& feature, Normalisation normalisation, int smoothing,
                                 const std::string& image_covariate, const Covariates* covariates = nullptr);
/// The same with the subject covariates of a design (its names, columns and source).
ReferenceRecipe reference_recipe(const std::string& feature, Normalisation normalisation, int smoothing,
                                 const std::string& image_covariate, const CovariateDesign& design);

/// The first way the recipe `made` (of sums) differs from `wanted` (a comparison's), as
/// "feature fdg, not pet"; nothing when they agree (the covariate table's path is not compared).
std::optional<std::string> recipe_difference(const ReferenceRecipe& wanted, const ReferenceRecipe& made);

/// One normal as a reference reads it, per element: the normalised (and smoothed) feature, and
/// the normalised (and smoothed) image covariate (empty without one); NaN: no data there.
struct NormalValues {
  std::string subject;            ///< ElementTable::subject (the covariates' participant_id)
  std::vector<double> feature, image;
};

/// The values of `table` under `recipe`; `name` names the table in messages, `elements` (null when
/// the recipe does not smooth) must have the table's definition. InputError when the table lacks
/// a feature, when the image covariate is the feature itself, or when the smoothing is out of
/// range.
NormalValues normal_values(const CanonicalElements* elements, const ElementTable& table, const std::string& name,
                           const ReferenceRecipe& recipe);

/// The normals of a streaming pass: their names, and each one's values and design row on demand.
/// `values` and `design_row` are called from several threads at once.
struct NormalSource {
  std::vector<std::string> names;
  std::function<NormalValues(std::size_t)> values;
  /// normal i's design row (the recipe's covariate_columns); unset without covariates
  std::function<std::vector<double>(std::size_t, const NormalValues&)> design_row;
};

/// The normals' subject tables at `paths`, each read (only the columns the recipe needs) when its
/// values are asked for, and checked to have `definition`; with covariates, each row looked up in
/// `covariates` by the table's subject. `elements` as normal_values.
NormalSource table_files(const std::vector<std::string>& paths, const ElementDefinition& definition,
                         const ReferenceRecipe& recipe, const CanonicalElements* elements,
                         const Covariates* covariates = nullptr);

/// Tables already in memory (`tables`, named `names`), with their design `design` (empty without
/// covariates; one row per table otherwise).
NormalSource tables_in_memory(const std::vector<ElementTable>& tables, const std::vector<std::string>& names,
                              const ReferenceRecipe& recipe, const CanonicalElements* elements,
                              const CovariateDesign& design = {});

class ReferenceSums;
ReferenceSums read_reference_sums(const std::string& path);

/// Per-element sufficient statistics of a group of normals.
class ReferenceSums {
 public:
  /// Empty sums for tables of `definition` under `recipe`. InputError when the recipe's smoothing
  /// is out of 0..8, its image covariate is its feature, or the model has more than 16 columns.
  ReferenceSums(const ElementDefinition& definition, ReferenceRecipe recipe);

  const ElementDefinition& definition() const { return definition_; }
  const ReferenceRecipe& recipe() const { return recipe_; }
  /// The normals summed, in the order added (merge appends the other's).
  const std::vector<std::string>& normals() const { return names_; }
  /// Their design rows (the recipe's covariate_columns each; empty rows without covariates).
  const std::vector<std::vector<double>>& design() const { return design_; }
  int model_columns() const { return q_; }
  /// Values per element: the packed upper triangle of sum x x^T, then sum x y, then sum y^2.
  int stride() const { return stride_; }
  /// Element e's `stride()` sums.
  const double* element(int e) const { return sums_.data() + static_cast<std::size_t>(e) * static_cast<std::size_t>(stride_); }

  /// Adds one normal: its name (unique among the sums' normals), values (one per element of the
  /// definition) and design row (the recipe's covariate_columns; InputError on a NaN).
  void add(const std::string& name, const NormalValues& values, const std::vector<double>& design_row = {});
  /// Adds the normals of `other`: InputError when the definitions or recipes differ, or a normal
  /// is in both.
  void merge(const ReferenceSums& other);

  /// The reference of the normals summed (at least 3), each element's spread shrunk by
  /// `shrinkage` (Reference::shrinkage) over `elements` (null when shrinkage is 0). InputError as
  /// build_reference: too few normals, covariates that do not vary independently over them.
  Reference reference(const CanonicalElements* elements, double shrinkage) const;
  /// The reference of every normal summed but normal `index` (normals()[index]), whose `values`
  /// (as added) are taken out of the totals: exactly the reference of the others, to round-off.
  Reference reference_without(const CanonicalElements* elements, double shrinkage, std::size_t index,
                              const NormalValues& values) const;

 private:
  friend ReferenceSums read_reference_sums(const std::string& path);
  Reference fit(const CanonicalElements* elements, double shrinkage, const std::vector<double>* out_row,
                const NormalValues* out_values) const;
  ElementDefinition definition_;
  ReferenceRecipe recipe_;
  int q_ = 1, stride_ = 3;
  std::vector<double> sums_;
  std::vector<std::string> names_;
  std::vector<std::vector<double>> design_;
};

/// Sums every normal of `source` (tables of `definition`) in one pass: normals are read in
/// parallel, a few at a time, and added in their order (the same sums whatever the thread count).
ReferenceSums sum_normals(const ElementDefinition& definition, const ReferenceRecipe& recipe, const NormalSource& source);

/// Writes `sums` as HDF5 (atomic): root attributes "format" ("vpm reference sums"),
/// "format_version" (1), "metadata" (JSON: definition, recipe, model_columns, stride, normals
/// count); datasets /sums (elements x stride, float64), /normals/names (the names as a JSON
/// array, UTF-8 bytes) and /normals/design (normals x covariate columns, float64; with
/// covariates). InputError naming the path when it cannot be written.
void write_reference_sums(const std::string& path, const ReferenceSums& sums);
/// Reads sums written by write_reference_sums; InputError naming the file and the object when it
/// is not such a file, is truncated or corrupt, or holds counts or sums that cannot be (negative
/// or non-integral counts, more than the normals, values that are not finite).
ReferenceSums read_reference_sums(const std::string& path);

/// {"feature", "normalisation", "smoothing", "image_covariate", "covariates", "covariate_columns",
///  "covariate_table"}
Json to_json(const ReferenceRecipe& recipe);

}  // namespace vpm
