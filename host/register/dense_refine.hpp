#pragma once
// The image refinement of dense registration (DenseRefineOptions, vpm/dense_registration.hpp).
#include <vector>

#include "vpm/dense_registration.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

/// Refines `x` (the subject's registered ball mesh with `tets`; `fixed` vertices stay) onto
/// `templ` through `images` (both native positions set); `reference` is the subject's mapped
/// ball, whose tet volumes the volume term keeps. InputError when the subject's image covers under 100 voxels of
/// its native mesh or either image is constant there.
DenseRefineReport refine_against_image(const DenseImages& images, const DenseTemplate& templ, const Points& reference,
                                       const Tets& tets, const std::vector<char>& fixed, Points& x,
                                       const DenseRefineOptions& options);

}  // namespace vpm
