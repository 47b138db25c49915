#pragma once
// The dense-registration options shared by `vpm register` and `vpm demo`.
#include <vector>

#include "cli.hpp"
#include "vpm/dense_registration.hpp"

namespace vpm::cli {

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
