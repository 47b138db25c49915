// One normal's values and where a streaming pass gets them (vpm/reference_sums.hpp):
// normal_values, table_files, tables_in_memory and sum_normals.
#include <algorithm>
#include <exception>

#include "core/parallel.hpp"
#include "vpm/error.hpp"
#include "vpm/reference_sums.hpp"

namespace vpm {

// ---- one normal's values -----------------------------------------------------------------

NormalValues normal_values(const CanonicalElements* el, const ElementTable& t, const std::string& name,
                           const ReferenceRecipe& recipe) {
  if (recipe.smoothing < 0 || recipe.smoothing > 8)
    throw InputError("reference: smoothing " + std::to_string(recipe.smoothing) + " is not in 0..8");
  if (recipe.image_covariate == recipe.feature)
    throw InputError("reference: the image covariate '" + recipe.feature + "' is the feature compared itself");
  if (recipe.smoothing > 0 && (!el || el->definition() != t.definition))
    throw InputError(name + ": the elements to smooth over differ from the table's definition");
  auto read = [&](const std::string& feature) {
    if (std::none_of(t.features.begin(), t.features.end(), [&](const ElementFeature& f) { return f.name == feature; }))
      throw InputError(name + ": no feature '" + feature + "' in the table");
    std::vector<double> v = normalised_feature(t, feature, recipe.normalisation);
    return recipe.smoothing > 0 ? smooth_over_elements(*el, v, recipe.smoothing) : v;
  };
  NormalValues v;
  v.subject = t.subject;
  v.feature = read(recipe.feature);
  if (!recipe.image_covariate.empty()) v.image = read(recipe.image_covariate);
  return v;
}

// ---- sources and the streaming pass --------------------------------------------------------

NormalSource table_files(const std::vector<std::string>& paths, const ElementDefinition& definition,
                         const ReferenceRecipe& recipe, const CanonicalElements* el, const Covariates* covariates) {
  NormalSource s;
  s.names = paths;
  s.values = [paths, definition, recipe, el](size_t i) {
    TableColumns columns;
    columns.features = {recipe.feature};
    if (!recipe.image_covariate.empty()) columns.features.push_back(recipe.image_covariate);
    columns.spread = false;
    columns.labels = false;
    const ElementTable t = read_subject_table(paths[i], columns);
    if (t.definition != definition)
      throw InputError(paths[i] + ": element definition differs from the reference's (level/shells/samples " +
                       to_string(t.definition) + " vs " + to_string(definition) + ")");
    return normal_values(el, t, paths[i], recipe);
  };
  if (covariates && !recipe.covariate_columns.empty())
    s.design_row = [paths, covariates](size_t i, const NormalValues& v) { return covariate_row(*covariates, v.subject, paths[i]); };
  return s;
}

NormalSource tables_in_memory(const std::vector<ElementTable>& tables, const std::vector<std::string>& names,
                              const ReferenceRecipe& recipe, const CanonicalElements* el, const CovariateDesign& design) {
  if (tables.size() != names.size()) throw InputError("reference: names and tables differ in number");
  if (!design.empty() && design.rows.size() != tables.size())
    throw InputError("reference: " + std::to_string(design.rows.size()) + " covariate rows for " +
                     std::to_string(tables.size()) + " normals");
  NormalSource s;
  s.names = names;
  s.values = [&tables, &names, recipe, el](size_t i) {
    if (tables[i].definition != tables[0].definition)
      throw InputError(names[i] + ": element definition differs from " + names[0] + "'s (level/shells/samples " +
                       to_string(tables[i].definition) + " vs " + to_string(tables[0].definition) + ")");
    return normal_values(el, tables[i], names[i], recipe);
  };
  if (!design.empty()) s.design_row = [&design](size_t i, const NormalValues&) { return design.rows[i]; };
  return s;
}

ReferenceSums sum_normals(const ElementDefinition& definition, const ReferenceRecipe& recipe, const NormalSource& source) {
  ReferenceSums sums(definition, recipe);
  if (!recipe.covariate_columns.empty() && !source.design_row)
    throw InputError("reference: covariates modelled but no design rows given");
  constexpr size_t kInFlight = 4;  // normals read at once
  const size_t N = source.names.size();
  for (size_t b = 0; b < N; b += kInFlight) {
    const size_t m = std::min(kInFlight, N - b);
    std::vector<NormalValues> v(m);
    std::vector<std::vector<double>> rows(m);
    std::vector<std::exception_ptr> errors(m);
    detail::parallel_for(static_cast<int>(m), 2, [&](int begin, int end) {
      for (int k = begin; k < end; ++k) try {
          v[static_cast<size_t>(k)] = source.values(b + static_cast<size_t>(k));
          if (source.design_row) rows[static_cast<size_t>(k)] = source.design_row(b + static_cast<size_t>(k), v[static_cast<size_t>(k)]);
        } catch (...) {
          errors[static_cast<size_t>(k)] = std::current_exception();
        }
    });
    for (const std::exception_ptr& x : errors)
      if (x) std::rethrow_exception(x);
    for (size_t k = 0; k < m; ++k) sums.add(source.names[b + k], v[k], rows[k]);
  }
  return sums;
}

}  // namespace vpm
