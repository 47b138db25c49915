// A reference from its normals' values (collective/reference_values.hpp).
#include "collective/reference_values.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "collective/covariate_model.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// Reference::shrinkage: each variance pulled towards the mean over the element and its neighbours.
void shrink_spread(const CanonicalElements& el, double shrinkage, std::vector<double>& std) {
  std::vector<double> var(std.size());
  for (size_t e = 0; e < std.size(); ++e) var[e] = std[e] * std[e];
  for (size_t e = 0; e < std.size(); ++e) {
    if (std::isnan(var[e])) continue;
    double sum = var[e];
    int k = 1;
    for (int nb : el.neighbours(static_cast<int>(e)))
      if (!std::isnan(var[static_cast<size_t>(nb)])) {
        sum += var[static_cast<size_t>(nb)];
        ++k;
      }
    std[e] = std::sqrt((1 - shrinkage) * var[e] + shrinkage * sum / k);
  }
}

// A table's feature `name`, normalised and smoothed as the recipe says; `label` names the table.
std::vector<double> read_feature(const CanonicalElements* el, const ElementTable& t, const std::string& label,
                                 const std::string& name, const ReferenceRecipe& recipe) {
  if (std::none_of(t.features.begin(), t.features.end(), [&](const ElementFeature& f) { return f.name == name; }))
    throw InputError(label + ": no feature '" + name + "' in the table");
  std::vector<double> v = normalised_feature(t, name, recipe.normalisation);
  return recipe.smoothing > 0 ? smooth_over_elements(*el, v, recipe.smoothing) : v;
}

std::string definition_text(const ElementDefinition& d) {
  return std::to_string(d.level) + "/" + std::to_string(d.shells) + "/" + std::to_string(d.samples);
}

// Without covariates: per element the normals' mean and sample standard deviation.
void fit_mean_spread(const std::vector<const NormalValues*>& use, Reference& r) {
  const size_t n = use[0]->feature.size();
  r.mean.assign(n, kNaN);
  r.std.assign(n, kNaN);
  r.count.assign(n, 0);
  for (size_t e = 0; e < n; ++e) {
    double s = 0, s2 = 0;
    int c = 0;
    for (const NormalValues* v : use)
      if (!std::isnan(v->feature[e])) {
        s += v->feature[e];
        ++c;
      }
    r.count[e] = c;
    if (c < 2) continue;
    const double mean = s / c;
    for (const NormalValues* v : use)
      if (!std::isnan(v->feature[e])) s2 += (v->feature[e] - mean) * (v->feature[e] - mean);
    r.mean[e] = mean;
    r.std[e] = std::sqrt(s2 / (c - 1));
  }
}

}  // namespace

std::vector<NormalValues> normal_values(const CanonicalElements* el, const std::vector<ElementTable>& normals,
                                        const std::vector<std::string>& names, const ReferenceRecipe& recipe) {
  if (recipe.smoothing < 0) throw InputError("reference: smoothing " + std::to_string(recipe.smoothing) + " is negative");
  if (!(recipe.shrinkage >= 0 && recipe.shrinkage <= 1))
    throw InputError("reference: shrinkage " + std::to_string(recipe.shrinkage) + " is not in [0, 1]");
  if (normals.size() < 3) throw InputError("reference: needs at least 3 normals, got " + std::to_string(normals.size()));
  if (recipe.image_covariate == recipe.feature)
    throw InputError("reference: the image covariate '" + recipe.feature + "' is the feature compared itself");
  const ElementDefinition& definition = normals[0].definition;
  if ((recipe.smoothing > 0 || recipe.shrinkage > 0) && el->definition() != definition)
    throw InputError("reference: the elements to smooth over differ from the tables' definition");
  std::vector<NormalValues> values(normals.size());
  for (size_t i = 0; i < normals.size(); ++i) {
    if (normals[i].definition != definition)
      throw InputError(names[i] + ": element definition differs from " + names[0] + "'s (level/shells/samples " +
                       definition_text(normals[i].definition) + " vs " + definition_text(definition) + ")");
    values[i].feature = read_feature(el, normals[i], names[i], recipe.feature, recipe);
    if (!recipe.image_covariate.empty())
      values[i].image = read_feature(el, normals[i], names[i], recipe.image_covariate, recipe);
  }
  return values;
}

std::vector<const NormalValues*> every_normal(const std::vector<NormalValues>& values) {
  std::vector<const NormalValues*> use;
  for (const NormalValues& v : values) use.push_back(&v);
  return use;
}

Reference reference_from_values(const CanonicalElements* el, const ElementDefinition& definition,
                                const std::vector<const NormalValues*>& use, const ReferenceRecipe& recipe,
                                const CovariateDesign& design) {
  if (use.size() < 3) throw InputError("reference: needs at least 3 normals, got " + std::to_string(use.size()));
  Reference r;
  r.definition = definition;
  r.feature = recipe.feature;
  r.normalisation = recipe.normalisation;
  r.smoothing = recipe.smoothing;
  r.shrinkage = recipe.shrinkage;
  r.image_covariate = recipe.image_covariate;
  r.subjects = static_cast<int>(use.size());
  r.covariates = design.columns;
  if (r.has_model())
    fit_covariate_model(use, design, r);
  else
    fit_mean_spread(use, r);
  if (recipe.shrinkage > 0) shrink_spread(*el, recipe.shrinkage, r.std);
  return r;
}

}  // namespace vpm::detail
