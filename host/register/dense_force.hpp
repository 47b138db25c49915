#pragma once
// The steps of register_dense (dense_registration.cpp): region boundaries, closest-point
// matches, their smoothing at field centres, the label agreement.
#include <Eigen/Core>
#include <vector>

#include "vpm/mesh.hpp"
#include "vpm/rbf.hpp"

namespace vpm {

/// `labels` with every label in `exclude` (and every negative one) set to 0 (unlabelled).
std::vector<int> without_labels(const std::vector<int>& labels, const std::vector<int>& exclude);

/// The faces between tets of different labels (and boundary faces of labelled tets), once for
/// each labelled side: row f of `faces` lies on the boundary of region `label[f]`. Sorted by
/// label. `tets` m x 4, `labels` m entries (0 = unlabelled).
struct RegionFaces {
  std::vector<int> label;
  Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> faces;
};
RegionFaces region_faces(const Tets& tets, const std::vector<int>& labels);

/// Region boundaries at given vertex positions: face centroids and areas grouped by region.
struct RegionSurface {
  std::vector<int> labels;     ///< regions, ascending
  std::vector<long> offset;    ///< faces of labels[r]: rows offset[r] .. offset[r + 1] - 1
  Points centroid;             ///< f x 3
  Eigen::VectorXd area;        ///< f
};
RegionSurface region_surface(const Points& vertices, const RegionFaces& faces);

/// Symmetric closest-point matches of the regions both surfaces carry: each subject face to the
/// closest template face of its region, and each template face to the closest subject face
/// (placed at that subject face). Displacements point from the subject to the template.
struct BoundaryMatches {
  Points at, displacement;  ///< k x 3
  Eigen::VectorXd weight;   ///< k: face area / mean face area
  std::vector<int> regions; ///< regions matched
  double mean_distance = 0; ///< weighted mean |displacement|
};
BoundaryMatches closest_matches(const RegionSurface& subject, const RegionSurface& templ);

/// Points of a regular grid of spacing `spacing` (one at the origin) inside the unit ball.
Points ball_grid(double spacing);

/// The matches averaged at `centres` with a Gaussian of width `sigma`:
/// sum w_i g_i d_i / (sum w_i g_i + 1) (c x 3); `mass` (optional) gets each centre's
/// sum w_i g_i / (sum w_i g_i + 1), in [0, 1): how much data the centre saw.
Points smooth_matches(const BoundaryMatches& matches, const Points& centres, double sigma,
                      Eigen::VectorXd* mass = nullptr);

/// Mean Dice over `regions` of two label samplings of the same points (vpm/labels.hpp); 0 when
/// there are no regions.
double mean_dice(const std::vector<int>& a, const std::vector<int>& b, const std::vector<int>& regions);

}  // namespace vpm
