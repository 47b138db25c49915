#pragma once
// Canonical-element fixtures shared by the statistics and covariate tests.
#include <set>

#include "vpm/elements.hpp"

namespace vpm::test {

/// A small element definition (level 2, 3 shells, 8 samples per element): quick tables.
ElementDefinition small_elements();

/// The element e0 and its neighbours in its shell: a planted focus of adjacent elements.
std::set<int> planted_focus(const CanonicalElements& elements, int e0);

}  // namespace vpm::test
