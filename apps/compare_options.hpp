#pragma once
// The comparison options shared by `vpm compare` and `vpm calibrate` (the calibration must use
// the patients' own options), and reading the normals' tables.
#include <optional>
#include <string>
#include <vector>

#include "cli.hpp"
#include "vpm/calibration.hpp"
#include "vpm/covariates.hpp"
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

/// The tables of --normals A.tsv,B.tsv,... (at least `at_least`), read; `paths` receives the names.
std::vector<ElementTable> read_normals(const Args& args, size_t at_least, std::vector<std::string>& paths);

/// The option-table rows of --normalisation, --threshold, --fdr, --smooth, --shrink, --extend,
/// --test, --peak, --sign, --covariates, --participants and --image-covariate (not --min-cluster, --normals,
/// --feature), for both commands' Registrar; `peak_auto`: --peak's row offers auto (vpm calibrate).
std::vector<OptionSpec> comparison_option_rows(bool peak_auto = false);

}  // namespace vpm::cli
