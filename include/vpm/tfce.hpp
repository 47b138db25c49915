#pragma once
// Threshold-free cluster enhancement (Smith & Nichols, NeuroImage 44, 2009) on the canonical
// elements' adjacency graph: each element's score integrates, over the heights h it reaches, the
// size of its connected component at h weighted by h, so that a small strong focus and a large
// weak one both score high without a cluster-forming cut or a cluster size. `vpm calibrate
// --tfce` sets the level a focus's elements must reach from the normals left out, as the
// family-wise maximum (vpm/calibration.hpp), and CompareOptions::tfce_level applies it.
#include <vector>

#include "vpm/elements.hpp"

namespace vpm {

/// The enhancement's constants: the paper's E = 0.5 and H = 2 for 3-D images, in steps of 0.1
/// of |z| (the scores change by under 1 % against steps of 0.05 on the synthetic cohorts' maps).
struct TfceParameters {
  double extent_power = 0.5;  ///< E: the component's size (elements) to this power
  double height_power = 2.0;  ///< H: the height to this power
  double step = 0.1;          ///< dh: the heights are step, 2 step, ... (> 0)
};

/// Per element, the TFCE score of sign * z (sign +1 or -1): the sum over the heights
/// h = step, 2 step, ... <= sign * z[e] of size(h)^E h^H step, size(h) the number of elements in
/// e's connected component of {sign * z >= h}; 0 where sign * z < step or z is NaN.
/// InputError when z's size is not the elements' or the parameters are out of range.
std::vector<double> tfce_scores(const CanonicalElements& el, const std::vector<double>& z, int sign,
                                const TfceParameters& parameters = {});

}  // namespace vpm
