#pragma once
// Pieces of load_cohort_view (vpm/cohort_view.hpp) kept out of the public header.
#include <map>
#include <string>
#include <vector>

#include "vpm/cohort_view.hpp"

namespace vpm::detail {

/// The foci table of `vpm compare` (OUT_foci.tsv), each focus's peak element from `c`.
std::vector<ViewFocus> read_view_foci(const std::string& path, const Comparison& c);

/// A patient's image and its z-map (NIfTI on the same grid), every step-th voxel so that at most
/// `max_voxels` remain.
ViewSlices read_view_slices(const std::string& image_path, const std::string& z_path, long max_voxels);

/// The template's atlas label (cell field `label` of its ball mesh) at every element's centre.
std::vector<int> element_labels(const CanonicalElements& elements, const std::string& template_mesh);

/// Atlas names from lines "id name [...]" (mricron's *.nii.txt); '#' lines skipped.

}  // namespace vpm::detail
