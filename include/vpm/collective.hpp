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

/// Landmarks for a subject without atlas labels (or with labels of another scheme than the
/// template's): pairs of points that correspond under the affine map matching the two native
/// solids' moments. Both meshes are mapped (ball positions, point field original_position).
/// The affine takes the moving solid's volume centroid and second-moment ellipsoid onto the
/// fixed one's (A = S_f^(1/2) S_m^(-1/2), symmetric square roots: no rotation, so the two
/// native frames must agree in orientation, as scanner RAS frames do). `points` fixed ball
/// points (the centre and 12 icosahedron directions at radii 0.35 and 0.7: 25) are carried to the
/// fixed native space through its map, by the affine to the moving native space, and into the
/// moving ball through its map; those that land outside the moving native mesh are dropped.
/// `labels` of the result is empty. InputError when a mesh has no original_position, or when
/// fewer than 4 points land inside the moving mesh.
struct MomentLandmarks {
  Points source, target;           ///< row i: the moving / fixed ball positions of pair i
  Eigen::Matrix3d linear = Eigen::Matrix3d::Identity();  ///< the native affine: x_f = linear (x_m - c_m) + c_f
  Eigen::Vector3d moving_centroid = Eigen::Vector3d::Zero(), fixed_centroid = Eigen::Vector3d::Zero();
  int dropped = 0;                 ///< points outside the moving native mesh
};
MomentLandmarks moment_landmarks(const TetMesh& moving, const TetMesh& fixed);

/// The centres of the cells of a regular grid of `per_axis`^3 cells over [-1, 1]^3 that lie
/// inside the unit ball (k x 3, k about 0.52 per_axis^3), i fastest.
Points ball_grid_points(int per_axis);

}  // namespace vpm
