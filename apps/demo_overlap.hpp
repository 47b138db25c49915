#pragma once
// The demo's overlap measure: Dice in the subject's own image space, Colin27's atlas carried onto
// the subject's voxels through the maps and the registration, the measure an image registration
// (elastix, its atlas carried by transformix) is scored by. The benchmark of registered pairs
// (bench/pairs/) adds the measures in the common ball (docs/register.md, "Two Dice measures").
#include <vector>

#include "vpm/image.hpp"
#include "vpm/labels.hpp"
#include "vpm/mesh.hpp"

namespace vpm::cli {

/// Colin27's atlas labels carried onto the voxels of `subj_atlas` that lie inside the subject's
/// native mesh, through the subject's ball positions `subject_ball` (its map, or a registration
/// of it) and Colin27's map `tmpl`; `voxels` receives the voxels' indices into subj_atlas.data.
std::vector<int> carried_labels(const TetMesh& tmpl, const TetMesh& subj, const Points& subject_ball,
                                const Image& tmpl_atlas, const Image& subj_atlas, std::vector<size_t>& voxels);

/// Dice of the `evaluated` regions between Colin27's atlas carried onto the subject's voxels
/// through `subject_ball` (carried_labels; one rounding to a voxel grid, as transformix has) and
/// the subject's own atlas there; `voxel_count` receives the number of voxels inside the
/// subject's mesh.
std::vector<LabelOverlap> subject_space_dice(const TetMesh& tmpl, const TetMesh& subj, const Points& subject_ball,
                                             const Image& tmpl_atlas, const Image& subj_atlas,
                                             const std::vector<int>& evaluated, long& voxel_count);

}  // namespace vpm::cli
