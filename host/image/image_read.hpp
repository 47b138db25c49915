#pragma once
// Private: reading an image at world positions (kernels/image_read.clh, compiled here and in
// kernels/sampling.cl): what sample_image, inside_grid and resample_image (vpm/image.hpp) and
// the element sampler's host side run.
#include <cmath>

#include "vpm/image.hpp"

namespace vpm::detail {

#include "kernels/image_read.clh"

/// The reader's view of `image`: the inverse of its affine (Eigen's 3 x 3 inverse, as
/// Image::to_voxel forms it), its grid and a pointer into its voxels.
IrImage ir_image(const Image& image);

}  // namespace vpm::detail
