#pragma once
// The intensity force of dense registration (DenseForce::image): both subjects' images read on
// one regular grid in the ball through their maps (ball point -> containing tet -> native
// position -> trilinear voxel value) and compared there. At each centre of the level's field,
// the translation that best explains the local difference in the least-squares sense
// (Lucas-Kanade, with the symmetric gradient of the two images). bench/results/register_image_force/ says why not
// demons: smoothing per-point demons steps moved about a third as far per iteration and ended
// at a worse mismatch.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "vpm/dense_registration.hpp"
#include "vpm/locate.hpp"

namespace vpm {

class ImageForce {
 public:
  /// `cells` grid cells along the ball's diameter (cell centres inside the unit ball are the
  /// grid points). Reads the template's image at the grid once, and the subject's through its
  /// ball mesh at `ball` (with `tets`) to fix the linear intensity scale subject -> template
  /// (same mean and spread over the grid).
  ImageForce(const DenseImages& images, const Points& template_ball, const Tets& template_tets, const Points& ball,
             const Tets& tets, int cells);

  /// The subject's image read at the grid through its ball mesh at `ball`, scaled by the fixed
  /// linear scale.
  std::vector<double> subject_values(const Points& ball) const;
  /// The same with the subject's ball mesh already prepared for location.
  std::vector<double> subject_values(const TetLocator& ball) const;
  /// Mean squared difference to the template's values over the grid, / the template's variance.
  double mismatch(const std::vector<double>& subject) const;
  /// The local least-squares systems of the translation that moves the subject onto the
  /// template at each of `centres` (c x 3): with Gaussian weights w_i = exp(-|x_i - centre|^2 /
  /// (2 sigma^2)) over the grid points within 3 sigma, a = sum w_i g_i g_i^T and
  /// b = sum w_i g_i (S_i - T_i), the normal equations of S(x - t) = T linearised
  /// (Lucas-Kanade), g the mean gradient of the two images (central differences), both smoothed
  /// by a Gaussian of width `image_sigma` first (0: not). For fit_divfree_weighted.
  LocalSystems local_systems(const std::vector<double>& subject, const Points& centres, double sigma,
                             double image_sigma) const;

  /// The regularisation eps = kTextureFloor x the mean trace under which a centre's system is
  /// solved alone to report the translation it asks for (DenseIteration::mean_translation).
  static constexpr double kTextureFloor = 0.05;

  const Points& grid() const { return grid_; }
  /// The gradient of `values` (grid values, e.g. subject_values) at every grid point (central
  /// differences, ball units), in template standard deviations per ball unit (n x 3).
  Points gradients(const std::vector<double>& values) const;

 private:
  Eigen::Vector3d gradient(const std::vector<double>& values, long point) const;
  std::vector<double> smoothed(const std::vector<double>& values, double sigma) const;

  const DenseImages& images_;
  const Tets& tets_;
  int cells_ = 0;
  double h_ = 0;
  Points grid_;
  std::vector<long> index_;      ///< cell (i, j, k) -> grid point or -1 (outside the ball)
  std::vector<int> cell_of_;     ///< grid point -> cell i + cells (j + cells k)
  std::vector<double> templ_;    ///< template values at the grid
  double templ_mean_ = 0, templ_var_ = 1;
  double scale_ = 0, offset_ = 0;  ///< subject -> template intensity (set at the first read)
};

}  // namespace vpm
