#include "compare_options.hpp"

#include <fstream>
#include <sstream>

#include "vpm/error.hpp"
#include "vpm/io.hpp"

namespace vpm::cli {

CompareOptions compare_options(const Args& args, bool peak_auto) {
  CompareOptions o;
  o.threshold = args.get_double("--threshold", o.threshold);
  o.fdr_q = args.get_double("--fdr", 0);
  o.min_cluster = args.get_int("--min-cluster", o.min_cluster);
  o.extend = args.get_double("--extend", 0);
  o.relative_extent = args.get_double("--relative-extent", 0);
  o.tfce_level = args.get_double("--tfce-level", 0);
  o.test = parse_option("--test", [&] { return parse_single_case_test(args.get("--test", "z")); });
  o.peak = peak_auto && args.get("--peak", "") == "auto" ? 0.0 : args.get_double("--peak", 0);
  const std::string sign = args.get("--sign", "both");
  if (sign == "both") o.sign = 0;
  else if (sign == "hyper") o.sign = 1;
  else if (sign == "hypo") o.sign = -1;
  else throw InputError("option --sign: '" + sign + "' is not one of both, hyper, hypo");
  if (const auto bad = compare_option_error(o)) {
    // the library names CompareOptions' fields; the flags are those with dashes, but for --fdr
    std::string flag = bad->field == "fdr_q" ? "fdr" : bad->field;
    for (char& ch : flag)
      if (ch == '_') ch = '-';
    throw InputError("option --" + flag + ": " + bad->problem);
  }
  return o;
}

CalibrationSettings comparison_settings(const Args& args, bool peak_auto) {
  CalibrationSettings s;
  const auto feature = args.get("--feature");
  if (!feature) throw InputError("needs --feature");
  s.feature = *feature;
  s.normalisation = parse_option(
      "--normalisation", [&] { return parse_normalisation(args.get("--normalisation", "proportional")); });
  s.smoothing = args.get_int("--smooth", 0);
  if (s.smoothing < 0 || s.smoothing > 8) throw InputError("option --smooth: must be in 0..8");
  s.shrinkage = args.get_double("--shrink", 0);
  if (!(s.shrinkage >= 0 && s.shrinkage <= 1)) throw InputError("option --shrink: must be in 0..1");
  s.compare = compare_options(args, peak_auto);
  s.calibrate_peak = peak_auto && args.get("--peak", "") == "auto";
  if (const auto names = args.get("--covariates")) {
    std::stringstream ss(*names);
    std::string item;
    while (std::getline(ss, item, ','))
      if (!item.empty()) s.covariates.push_back(item);
    if (s.covariates.empty()) throw InputError("option --covariates: names no covariate");
  }
  s.image_covariate = args.get("--image-covariate", "");
  if (args.has("--image-covariate") && (s.image_covariate.empty() || s.image_covariate == s.feature))
    throw InputError("option --image-covariate: '" + s.image_covariate + "' must name another feature of the tables than --feature");
  return s;
}

std::optional<Covariates> read_participants(const Args& args, const CalibrationSettings& settings) {
  const auto table = args.get("--participants");
  if (settings.covariates.empty()) {
    if (table) throw InputError("option --participants needs --covariates (the columns to model)");
    return std::nullopt;
  }
  if (!table) throw InputError("option --covariates needs --participants (the table that holds them)");
  return read_covariates(*table, settings.covariates);
}

std::vector<std::string> normal_paths(const Args& args, size_t at_least) {
  const auto list = args.get("--normals");
  if (!list) throw InputError("needs --normals");
  std::vector<std::string> paths;
  if (!list->empty() && (*list)[0] == '@') {  // @LIST: one path a line
    const std::string file = list->substr(1);
    std::ifstream in(file);
    if (!in) throw InputError("option --normals: cannot read the list " + file);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (!line.empty()) paths.push_back(line);
      if (n > 10'000'000) throw InputError(file + ": more than 10 million lines; not a list of tables");
    }
  } else {
    std::stringstream ss(*list);
    std::string item;
    while (std::getline(ss, item, ','))
      if (!item.empty()) paths.push_back(item);
  }
  if (paths.size() < at_least)
    throw InputError("option --normals: needs at least " + std::to_string(at_least) + " tables, got " +
                     std::to_string(paths.size()));
  return paths;
}

ReferenceRecipe reference_recipe(const CalibrationSettings& s, const std::optional<Covariates>& cov) {
  return vpm::reference_recipe(s.feature, s.normalisation, s.smoothing, s.image_covariate, cov ? &*cov : nullptr);
}

ElementDefinition table_definition(const std::string& path) {
  TableColumns metadata_only;
  metadata_only.features = {""};  // no feature has an empty name
  metadata_only.spread = metadata_only.labels = false;
  return read_subject_table(path, metadata_only).definition;
}

LoadedReference load_reference(const Args& args, const ReferenceRecipe& recipe, const std::optional<Covariates>& cov,
                               size_t at_least) {
  if (const auto path = args.get("--reference")) {
    ReferenceSums sums = read_reference_sums(*path);
    if (const auto diff = recipe_difference(recipe, sums.recipe()))
      throw InputError("option --reference: " + *path + " was summed with " + *diff);
    if (sums.normals().size() < at_least)
      throw InputError("option --reference: " + *path + " sums " + std::to_string(sums.normals().size()) +
                       " normals, at least " + std::to_string(at_least) + " are needed");
    auto el = std::make_unique<CanonicalElements>(sums.definition());
    return {std::move(sums), std::move(el)};
  }
  const std::vector<std::string> paths = normal_paths(args, at_least);
  const ElementDefinition definition = table_definition(paths[0]);
  auto el = std::make_unique<CanonicalElements>(definition);
  ReferenceSums sums = sum_normals(definition, recipe, table_files(paths, definition, recipe, el.get(), cov ? &*cov : nullptr));
  return {std::move(sums), std::move(el)};
}

std::vector<OptionSpec> comparison_option_rows(bool peak_auto) {
  const OptionSpec peak =
      peak_auto ? OptionSpec{"--peak", "ZP|auto",
                             "a cluster under the cluster size is a focus too when its peak |z| >= ZP; auto: the level "
                             "the normals' false clusters peak beyond at half the rate (default off)"}
                : OptionSpec{"--peak", "ZP",
                             "a cluster smaller than --min-cluster is a focus too when its peak |z| >= ZP (default off)"};
  return {
      {"--normalisation", "proportional|none", "per-subject scaling to the global mean (default proportional)"},
      {"--threshold", "Z", "|z| of a focus element (default 3)"},
      {"--fdr", "Q", "Benjamini-Hochberg false discovery rate instead of --threshold"},
      {"--smooth", "R", "average every subject's feature over R rings of adjacent elements first (default 0)"},
      {"--shrink", "L", "pull each element's variance over the normals towards its neighbours' by L in 0..1 (default 0)", false, 0, false, true},
      {"--extend", "Z2", "grow each focus into adjacent elements with |z| >= Z2 (hysteresis; default off)", false, 0, false, true},
      {"--relative-extent", "F", "trim each focus to where its locally averaged |z| reaches F x its peak (e.g. 0.3; default off)", false, 0, false, true},
      {"--test", "z|crawford-howell", "plain z, or Crawford-Howell's t for one case against n normals as the equivalent z (default z)", false, 0, false, true},
      peak,
      {"--sign", "both|hyper|hypo", "increases, decreases or both (default both)"},
      {"--covariates", "NAME,...", "model the normals' values on these participant covariates (e.g. age,sex); each subject compared with its own prediction"},
      {"--participants", "TABLE.tsv", "with --covariates: the table with participant_id and those columns (BIDS participants.tsv)"},
      {"--image-covariate", "NAME", "model each element's normal value on the subjects' own feature NAME there too (e.g. t1w: what the structure explains is not a focus)"},
  };
}

}  // namespace vpm::cli
