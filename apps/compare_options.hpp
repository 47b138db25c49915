#pragma once
// The comparison options shared by `vpm compare` and `vpm calibrate` (the calibration must use
// the patients' own options), and reading the normals' tables.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli.hpp"
#include "vpm/calibration.hpp"
#include "vpm/covariates.hpp"
#include "vpm/reference_sums.hpp"
#include "vpm/statistics.hpp"

namespace vpm::cli {

/// --threshold, --fdr, --min-cluster, --extend, --test, --peak, --sign over CompareOptions'
/// defaults; InputError naming the option on a bad value. `peak_auto`: --peak may be "auto"
/// (vpm calibrate: the level is calibrated; peak left 0).
CompareOptions compare_options(const Args& args, bool peak_auto = false);

/// The feature (--feature), normalisation (--normalisation), smoothing (--smooth 0..8),
/// shrinkage (--shrink 0..1), image covariate (--image-covariate) and
/// compare options of a comparison, as a calibration records them (rate left at its default);
/// with `peak_auto`, --peak auto sets calibrate_peak.
CalibrationSettings comparison_settings(const Args& args, bool peak_auto = false);

/// --participants TABLE.tsv read for settings.covariates (--covariates NAME,...); nullopt
/// without covariates. InputError when one option comes without the other.
std::optional<Covariates> read_participants(const Args& args, const CalibrationSettings& settings);

/// The table paths of --normals: A.h5,B.h5,... or @LIST (a file naming one table a line, for
/// cohorts whose list outgrows a command line); at least `at_least`.
std::vector<std::string> normal_paths(const Args& args, size_t at_least);

/// What a reference sums under `settings` (feature, normalisation, smoothing, image covariate)
/// with `covariates` (their columns; none without).
ReferenceRecipe reference_recipe(const CalibrationSettings& settings, const std::optional<Covariates>& covariates);

/// The normals' sums and the elements of their definition: read from --reference SUMS.h5 (vpm
/// reference; InputError when its recipe differs from `recipe`), or summed in one pass over the
/// tables of --normals. At least `at_least` normals.
struct LoadedReference {
  ReferenceSums sums;
  std::unique_ptr<CanonicalElements> elements;
};
LoadedReference load_reference(const Args& args, const ReferenceRecipe& recipe, const std::optional<Covariates>& covariates,
                               size_t at_least);

/// The element definition of the table at `path` (its metadata alone is read from an HDF5 table).
ElementDefinition table_definition(const std::string& path);

/// The option-table rows of --normalisation, --threshold, --fdr, --smooth, --shrink, --extend,
/// --test, --peak, --sign, --covariates, --participants and --image-covariate (not --min-cluster, --normals,
/// --feature), for both commands' Registrar; `peak_auto`: --peak's row offers auto (vpm calibrate).
std::vector<OptionSpec> comparison_option_rows(bool peak_auto = false);

}  // namespace vpm::cli
