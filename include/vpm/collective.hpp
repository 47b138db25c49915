#pragma once
// Comparing subjects in the common ball (paper 6.2, docs/design.md 5 "Overlap"): labelled regions
// located by their centroids (landmarks for registration) and compared by Dice overlap of the
// tets' label field sampled at common points of the ball (vpm/labels.hpp).
#include <Eigen/Core>
#include <vector>

#include "vpm/labels.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

/// Integer cell labels of `mesh`: its cell field `label` (rounded), InputError if it has none.
std::vector<int> cell_labels(const TetMesh& mesh);

/// Volume-weighted centroids of the tets carrying each label in `labels`: row i is the centroid
/// of the tets t with tet_labels[t] == labels[i] at positions `vertices` (n x 3; `tets` m x 4,
/// `tet_labels` m entries). A label no tet carries gives a row of NaN.
Points label_centroids(const Points& vertices, const Tets& tets, const std::vector<int>& tet_labels,
                       const std::vector<int>& labels);

/// Landmarks that pair two labelled meshes region by region (paper 5: the registration's
/// feature points): the centroids of the regions both meshes carry.
struct RegionLandmarks {
  std::vector<int> labels;  ///< ascending, > 0, carried by both meshes, none of `exclude`
  Points source, target;    ///< row i: centroid of labels[i] in the moving / the fixed mesh
};

/// Region-centroid landmarks from the `label` cell fields of `moving` and `fixed` (cell_labels;
/// InputError when either has none), leaving out the labels in `exclude` (held-out regions).
RegionLandmarks region_landmarks(const TetMesh& moving, const TetMesh& fixed, const std::vector<int>& exclude = {});

/// The centres of the cells of a regular grid of `per_axis`^3 cells over [-1, 1]^3 that lie
/// inside the unit ball (k x 3, k about 0.52 per_axis^3), i fastest.
Points ball_grid_points(int per_axis);

}  // namespace vpm
