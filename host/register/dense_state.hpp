#pragma once
// What the dense registration's stages share (dense_registration.cpp, dense_holds.cpp): the
// state every iteration reads, the fit of a configuration by the force's own measure and the
// restoration's holds (vpm/dense_registration.hpp).
#include <memory>
#include <vector>

#include "register/dense_force.hpp"
#include "register/dense_image_force.hpp"
#include "register/registration_steps.hpp"
#include "vpm/dense_registration.hpp"
#include "vpm/labels.hpp"
#include "vpm/locate.hpp"
#include "vpm/polish.hpp"
#include "vpm/topology.hpp"

namespace vpm {

/// What every iteration needs and nothing changes: the reference map, its boundary and
/// volumes, the region faces, the template's boundaries and its labels at the grid points.
struct DenseState {
  const Points& reference;
  const Tets& tets;
  std::vector<int> labels;
  TetTopology topology;  ///< of tets (its boundary_vertex pins the sphere); every Fit locates with it
  Eigen::VectorXd v0;
  RegionFaces faces;
  RegionSurface templ;
  Points grid;
  std::vector<int> grid_templ;
  std::vector<int> regions;
  std::unique_ptr<const ImageForce> image;  ///< with DenseForce::image and both
  DenseForce force = DenseForce::labels;

  /// Mean Dice of the subject's labels with the template's at the agreement grid; `at` is the
  /// subject's ball mesh prepared for location.
  double agreement(const TetLocator& at) const { return mean_dice(grid_templ, sample_labels(at, labels, grid), regions); }
};

/// How well `ball` fits the template by the force's own measure (better_than), and the
/// subject's image values on the image grid there (kept for the next force: one image read per
/// iteration instead of two).
struct Fit {
  double agreement = 0, mismatch = -1;
  std::vector<double> values;
  Fit(const DenseState& st, const Points& ball) {  // one location structure for both grids
    const TetLocator at(ball, st.tets, st.topology);
    agreement = st.agreement(at);
    if (!st.image) return;
    values = st.image->subject_values(at);
    mismatch = st.image->mismatch(values);
  }
  bool better_than(const Fit& o, DenseForce force) const {
    return force == DenseForce::labels ? agreement > o.agreement : mismatch < o.mismatch;
  }
};

/// Tets inverted in `v1` that were not in `v0`.
inline int newly_inverted(const Eigen::VectorXd& v0, const Eigen::VectorXd& v1) {
  int n = 0;
  for (Eigen::Index t = 0; t < v1.size(); ++t) n += v1(t) <= 0 && v0(t) > 0;
  return n;
}

/// The image grid points as holds of a restoration of the subject at `ball` (VolumeHold): each
/// point inside the mesh is held across its image edge, all scaled so that the holds' rows weigh
/// `weight` x the number of tets against the tets' volume rows.
std::vector<VolumeHold> image_holds(const DenseState& st, const Points& ball, double weight);

/// The holds of a restoration of the subject at `ball`: the image's edges with an image force
/// and DenseRegistrationOptions::restore_image_weight > 0, none otherwise.
std::vector<VolumeHold> restore_holds(const DenseState& st, const Points& ball, const DenseRegistrationOptions& o);

}  // namespace vpm
