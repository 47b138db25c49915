#pragma once
// The intensity force of dense registration (DenseForce::image): both subjects' images read on
// one regular grid in the ball through their maps (ball point -> containing tet -> native
// position -> trilinear voxel value) and compared there; the displacement that would make the
// subject's values match the template's is the demons force (Thirion 1998, with the symmetric
// gradient of the two images).
#include <Eigen/Core>
#include <string>
#include <vector>

#include "register/dense_force.hpp"
#include "vpm/dense_registration.hpp"

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
  /// Mean squared difference to the template's values over the grid, / the template's variance.
  double mismatch(const std::vector<double>& subject) const;
  /// The demons displacement at every grid point, d = (S - T) g / (|g|^2 + (S - T)^2 / (2 r h)^2),
  /// S and T the two images' grid values smoothed by a Gaussian of width `sigma` (ball units;
  /// normalised convolution inside the ball; 0: unsmoothed), g the mean of their gradients
  /// (central differences on the grid), h the grid spacing, r = `reach`: at most r h long.
  /// Weights 1; `mean_distance` is the mean |d|.
  BoundaryMatches demons(const std::vector<double>& subject, double sigma, double reach) const;

  const Points& grid() const { return grid_; }

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
