#pragma once
// The element-definition options shared by `vpm elements` and `vpm sample`.
#include "cli.hpp"
#include "vpm/elements.hpp"

namespace vpm::cli {

/// --level L, --layout shells|graded, --shells K (shells only: with graded it is InputError, the
/// shells follow from --level), --samples S over the defaults of ElementDefinition.
ElementDefinition element_definition(const Args& args);

}  // namespace vpm::cli
