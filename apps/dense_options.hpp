#pragma once
// The dense-registration options shared by `vpm register` and `vpm demo`.
#include <vector>

#include "cli.hpp"
#include "vpm/dense_registration.hpp"
#include "vpm/registration_preset.hpp"

namespace vpm::cli {

/// `base` with the settings of --preset landmarks|standard|accurate (`base` itself without it),
/// InputError naming the flag for another word.
DenseRegistrationOptions preset_option(const Args& args, DenseRegistrationOptions base = {});

/// The --dense-* flags (iterations, widths, step, force, image grid and smoothing, restoration
/// cycles and image weight, the fit's tolerance, ridge, smoothing and centre spacing, RK4 steps)
/// into `options` (InputError naming the flag for bad values).
DenseRegistrationOptions dense_options(const Args& args, DenseRegistrationOptions options = {});

/// The comma-separated widths of `flag` (each in (0, 2]); InputError naming the flag otherwise.
std::vector<double> parse_widths(const Args& args, const char* flag);

/// --restore-rounds N and --restore-min-gain G into `options` (after its restore_volumes is
/// set: both are refused with --no-restore), InputError naming the flag for bad values.
void restore_step_options(const Args& args, RegistrationOptions& options);

/// `command` with the option table rows of those flags inserted after the row of `after`
/// (`default_iterations`, `default_force`: the command's defaults of --dense-iterations and
/// --dense-force).
Command with_dense_options(Command command, const std::string& after, int default_iterations,
                           DenseForce default_force = DenseForce::labels);

}  // namespace vpm::cli
