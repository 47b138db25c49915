#pragma once
// Canonical-element fixtures shared by the statistics and covariate tests.
#include <set>
#include <string>

#include <vector>

#include "vpm/elements.hpp"
#include "vpm/sampling.hpp"
#include "vpm/statistics.hpp"

namespace vpm::test {

/// A small element definition (level 2, 3 shells, 8 samples per element): quick tables.
ElementDefinition small_elements();

/// The element e0 and its neighbours in its shell: a planted focus of adjacent elements.
std::set<int> planted_focus(const CanonicalElements& elements, int e0);

/// A subject table of small_elements(): feature "pet" ~ N(100, 5) per element (drawn from
/// `seed`), minus `loss` on `focus`; std 1 and 8 samples an element.
ElementTable noisy_pet_table(const std::string& id, unsigned seed, const std::set<int>& focus = {}, double loss = 0);

/// The "pet" reference of every normal but normals[left_out] (build_reference of the others, no
/// smoothing): what a calibration compares that normal with.
Reference reference_without(const CanonicalElements& elements, const std::vector<ElementTable>& normals,
                            const std::vector<std::string>& names, size_t left_out, Normalisation normalisation);

}  // namespace vpm::test
