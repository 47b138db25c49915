#pragma once
// `vpm map SURFACE -o OUT`: a closed genus-0 triangle surface mapped to the unit sphere, a
// disk-like one (one boundary loop) to the unit disk, with its face areas kept
// (vpm/surface_map.hpp). cmd_map.cpp hands it every input that is a surface.
#include <string>

#include "cli.hpp"
#include "vpm/timing.hpp"

namespace vpm::cli {

/// Runs the surface map of `in` to `out` with `args` (the options of `vpm map` that apply to
/// surfaces; the tet-only ones are refused), started at `t_start`. Returns the exit status.
int map_surface(const Args& args, const std::string& in, const std::string& out, Clock::time_point t_start);

}  // namespace vpm::cli
