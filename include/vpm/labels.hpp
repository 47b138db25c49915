#pragma once
// Labels on a tet mesh read at points, and the Dice overlap of two such samplings: how subjects
// are compared region by region (the registration's agreement, the demo's and the cohort's
// overlaps).
#include <vector>

#include "vpm/locate.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

/// Label at each of `points` (k x 3) in the mesh (`vertices` n x 3, `tets` m x 4,
/// `tet_labels` m entries): the label of the containing tet; `outside_label` for points farther
/// outside the mesh than `outside_tolerance` in barycentric terms (points in the thin gap
/// between the sphere and an inscribed ball mesh take the label of the nearest tet).
std::vector<int> sample_labels(const Points& vertices, const Tets& tets, const std::vector<int>& tet_labels,
                               const Points& points, int outside_label = 0, double outside_tolerance = 0.05);
/// The same in a mesh already prepared for location (`at`, with its tets' labels).
std::vector<int> sample_labels(const TetLocator& at, const std::vector<int>& tet_labels, const Points& points,
                               int outside_label = 0, double outside_tolerance = 0.05);

/// Overlap of one label between two label samplings of the same points.
struct LabelOverlap {
  int label = 0;
  long long count_a = 0, count_b = 0, both = 0;  ///< sample points labelled `label` in a, b, both
  double dice = 0;  ///< 2 |A and B| / (|A| + |B|); 1 when both are empty
};

/// Dice overlap of each of `labels` between samplings `a` and `b` (same length: one label per
/// common sample point). InputError when the lengths differ.
std::vector<LabelOverlap> dice_overlap(const std::vector<int>& a, const std::vector<int>& b,
                                       const std::vector<int>& labels);

}  // namespace vpm
