#pragma once
// `vpm register SPHERE -o OUT --landmarks SRC.csv --targets DST.csv`: a surface mapped to the
// unit sphere or the unit disk (by `vpm map SURFACE`) registered by landmarks with its face areas
// kept, on the sphere also onto a template by a per-vertex scalar (`--template --overlay
// --template-overlay`; vpm/surface_registration.hpp). cmd_register.cpp hands it every input that
// is a surface.
#include <string>

#include "cli.hpp"
#include "vpm/timing.hpp"

namespace vpm::cli {

/// Runs the sphere registration of `in` to `out` with `args` (the options of `vpm register`
/// that apply to surfaces; the others are refused), started at `t_start`. Returns the exit status.
int register_surface(const Args& args, const std::string& in, const std::string& out, Clock::time_point t_start);

}  // namespace vpm::cli
