#pragma once
// The deformation that makes `vpm demo`'s second subject from Colin27 (world mm), and its seeded
// variants (--seed S --max-rotation DEG) used by bench/paper for Table 2 of the paper.
#include <functional>

#include <Eigen/Core>

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

/// The rotation angle (degrees) demo_deformation(c, seed, max_rotation_deg) applies.
double demo_rotation_deg(unsigned seed, double max_rotation_deg);

}  // namespace vpm::cli
