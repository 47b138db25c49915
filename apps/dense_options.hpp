#pragma once
// The dense-registration options shared by `vpm register` and `vpm demo`.
#include <vector>

#include "cli.hpp"
#include "vpm/dense_registration.hpp"

namespace vpm::cli {

/// --dense-iterations N, --dense-widths W[,W...], --dense-step S into `options` (InputError
/// naming the flag for bad values).
DenseRegistrationOptions dense_options(const Args& args, DenseRegistrationOptions options = {});

/// `command` with the option table rows of those flags inserted after the row of `after`
/// (`default_iterations`: the command's default of --dense-iterations).
Command with_dense_options(Command command, const std::string& after, int default_iterations);

}  // namespace vpm::cli
