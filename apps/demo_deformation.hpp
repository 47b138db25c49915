#pragma once
// The deformation that makes `vpm demo`'s second subject from Colin27 (world mm), and its seeded
// variants (--seed S --max-rotation DEG) used by bench/paper for Table 2 of the paper.
#include <functional>

#include <Eigen/Core>

#include "vpm/image.hpp"

namespace vpm::cli {

/// Pull-back map x -> y (output world position -> input world position) for resample_image
/// about the brain centre `c`. Seed 0 is the demo's fixed deformation: anisotropic scaling of
/// up to 6 % plus four Gaussian displacement bumps of 5-7 mm (largest displacement gradient about
/// 0.2, a diffeomorphism). Seed S > 0 draws the scale factors (0.94-1.06), the bump centres
/// (within 30 mm of c) and displacements (up to 5 mm a component) from std::mt19937(S), with the
/// same bump width. A rotation about c by an angle drawn uniformly in [0, max_rotation_deg]
/// (a random axis; none when 0) is applied first.
/// `incompressible`: the same draw made volume-preserving (the scale factors divided by the cube
/// root of their product, then the time-1 flow, 4 RK4 steps, of a velocity that is the sum of
/// the curls of Gaussian vector potentials, one per bump, each as fast at most as the bump's
/// displacement), so a volume-preserving registration can in principle undo it; the default
/// bumps change local volume by up to about 20 % (the caudates of seed 0 shrink by 14-20 %
/// against the brain).
std::function<Eigen::Vector3d(const Eigen::Vector3d&)> demo_deformation(const Eigen::Vector3d& c, unsigned seed,
                                                                        double max_rotation_deg,
                                                                        bool incompressible = false);

/// The demo's deformed subject: Colin27's T1 resampled through `pull` (trilinear) and its atlas
/// (nearest). The T1 is cut to Colin27's brain mask carried voxel for voxel (nearest):
/// interpolation alone leaves a halo of small values up to a voxel outside the brain, which made
/// the subject's solid 5 % larger than Colin27's and capped any volume-preserving registration
/// (docs/register.md, "Two Dice measures").
struct DeformedSubject {
  Image t1, atlas;
};
DeformedSubject deformed_subject(const Image& t1, const Image& atlas,
                                 const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& pull);

/// The rotation angle (degrees) demo_deformation(c, seed, max_rotation_deg) applies.
double demo_rotation_deg(unsigned seed, double max_rotation_deg);

}  // namespace vpm::cli
