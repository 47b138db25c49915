#pragma once
// The dense-registration options shared by `vpm register` and `vpm demo`.
#include <vector>

#include "cli.hpp"
#include "vpm/dense_registration.hpp"
#include "vpm/registration_preset.hpp"

namespace vpm::cli {

/// The dense options of --preset landmarks|standard|accurate (the library's defaults without it),
/// InputError naming the flag for another word.
DenseRegistrationOptions preset_option(const Args& args);

/// --dense-iterations N, --dense-widths W[,W...], --dense-step S, --dense-force F,
/// --dense-image-grid N into `options` (InputError naming the flag for bad values).
DenseRegistrationOptions dense_options(const Args& args, DenseRegistrationOptions options = {});

/// --restore-rounds N and --restore-min-gain G into `options` (after its restore_volumes is
/// set: both are refused with --no-restore), InputError naming the flag for bad values.
void restore_step_options(const Args& args, RegistrationOptions& options);

/// `command` with the option table rows of those flags inserted after the row of `after`
/// (`default_iterations`, `default_force`: the command's defaults of --dense-iterations and
/// --dense-force).
Command with_dense_options(Command command, const std::string& after, int default_iterations,
                           DenseForce default_force = DenseForce::labels);

}  // namespace vpm::cli
