#pragma once
// The demo's overlap measures: Dice of held-out and landmark regions in the common ball, with
// labels read from the tets and from each subject's own atlas image through its map (ball point
// -> native position -> voxel); and Dice in the subject's own image space, Colin27's atlas
// carried onto the subject's voxels through the registration, the measure an image
// registration (elastix, its atlas carried by transformix) is scored by (docs/register.md,
// "Two Dice measures").
#include <vector>

#include "vpm/image.hpp"
#include "vpm/labels.hpp"
#include "vpm/mesh.hpp"

namespace vpm::cli {

/// Dice of the evaluated (held-out) regions and the mean Dice of the landmark regions, before
/// and after registration.
struct Overlap {
  long points = 0;
  /// tet labels (capped by the mesh resolution) and image labels through the maps, per evaluated region
  std::vector<LabelOverlap> before, after, image_before, image_after;
  double landmark_before = 0, landmark_after = 0, image_landmark_before = 0, image_landmark_after = 0;
  /// In the subject's image space: every voxel of the subject's atlas grid inside its mesh gets
  /// Colin27's atlas label carried through the maps (subject native -> subject ball, before or
  /// after registration -> Colin27 native -> nearest Colin27 voxel), compared with its own label
  /// (voxels outside the subject's mesh carry label 0). One rounding to a voxel grid, as an
  /// image registration's transformix has; the ball measure above rounds twice (a ball point
  /// read through both maps into both atlas grids).
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

/// Colin27's atlas labels carried onto the voxels of `subj_atlas` that lie inside the subject's
/// native mesh, through the subject's ball positions `subject_ball` (its map, or a registration
/// of it) and Colin27's map `tmpl`; `voxels` receives the voxels' indices into subj_atlas.data.
std::vector<int> carried_labels(const TetMesh& tmpl, const TetMesh& subj, const Points& subject_ball,
                                const Image& tmpl_atlas, const Image& subj_atlas, std::vector<size_t>& voxels);

}  // namespace vpm::cli
