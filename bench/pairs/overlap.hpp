#pragma once
// The overlap measures of the benchmark of registered pairs: Dice of the held-out and landmark
// regions in the common ball, with labels read from the tets and from each subject's own atlas
// image through its map (ball point -> native position -> voxel), beside the Dice in the
// subject's image space that `vpm demo` reports (apps/demo_overlap.hpp; docs/register.md,
// "Two Dice measures").
#include <vector>

#include "vpm/image.hpp"
#include "vpm/labels.hpp"
#include "vpm/mesh.hpp"

namespace vpm::bench {

/// Dice of the evaluated (held-out) regions and the mean Dice of the landmark regions, before
/// and after registration.
struct Overlap {
  long points = 0;
  /// tet labels (capped by the mesh resolution) and image labels through the maps, per evaluated region
  std::vector<LabelOverlap> before, after, image_before, image_after;
  double landmark_before = 0, landmark_after = 0, image_landmark_before = 0, image_landmark_after = 0;
  /// In the subject's image space (vpm::cli::subject_space_dice): one rounding to a voxel grid,
  /// as an image registration's transformix has; the ball measures above round twice (a ball
  /// point read through both maps into both atlas grids).
  std::vector<LabelOverlap> subject_before, subject_after;
  long subject_voxels = 0;  ///< voxels of the subject's atlas grid inside its mesh
  double seconds = 0;
};

/// The overlap on a grid of `grid`^3 ball points between the template's map `tmpl` and the
/// subject's map `subj` before and after registration (`registered`: the subject's ball
/// vertices after it), tets labelled `tmpl_labels` / `subj_labels`, atlas images in each
/// subject's native space.
Overlap measure_overlap(const TetMesh& tmpl, const TetMesh& subj, const Points& registered,
                        const std::vector<int>& tmpl_labels, const std::vector<int>& subj_labels,
                        const std::vector<int>& landmark_labels, const std::vector<int>& evaluated, int grid,
                        const Image& tmpl_atlas, const Image& subj_atlas);

/// The best Dice any volume-preserving registration can reach for a region: its two volumes in
/// the ball (the maps keep each subject's relative volumes) cannot change, so the overlap is at
/// most 2 min(a, b) / (a + b), from the counts of `o` (taken before registration).
double volume_bound(const LabelOverlap& o);

}  // namespace vpm::bench
