#include <algorithm>
#include <cmath>
#include <vector>

#include "core/parallel.hpp"
#include "image/image_read.hpp"

namespace vpm {

namespace detail {

IrImage ir_image(const Image& image) {
  IrImage im;
  const Eigen::Matrix3d inv = image.affine.topLeftCorner<3, 3>().inverse();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) im.inv[3 * r + c] = inv(r, c);
    im.t[r] = image.affine(r, 3);
    im.dims[r] = image.dims[r];
  }
  im.data = image.data.data();
  return im;
}

}  // namespace detail

namespace {
float sample(const detail::IrImage& im, const double* v, Interpolation mode) {
  return mode == Interpolation::nearest ? detail::ir_nearest(&im, v) : detail::ir_linear(&im, v);
}
}  // namespace

float sample_image(const Image& image, const Eigen::Vector3d& x, Interpolation interpolation) {
  const detail::IrImage im = detail::ir_image(image);
  double v[3];
  detail::ir_to_voxel(&im, x.data(), v);
  return sample(im, v, interpolation);
}

bool inside_grid(const Image& image, const Eigen::Vector3d& x) {
  const detail::IrImage im = detail::ir_image(image);
  double v[3];
  detail::ir_to_voxel(&im, x.data(), v);
  return detail::ir_inside(&im, v);
}

Image resample_image(const Image& image, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& pull,
                     Interpolation interpolation) {
  Image out = image;
  const detail::IrImage im = detail::ir_image(image);
  const int nk = image.dims[2];
  auto work = [&](int k_begin, int k_end) {
    for (int k = k_begin; k < k_end; ++k)
      for (int j = 0; j < image.dims[1]; ++j)
        for (int i = 0; i < image.dims[0]; ++i) {
          const Eigen::Vector3d x = image.to_world(Eigen::Vector3d(i, j, k));
          const Eigen::Vector3d y = pull(x);
          double v[3];
          detail::ir_to_voxel(&im, y.data(), v);
          out.data[image.index(i, j, k)] = sample(im, v, interpolation);
        }
  };
  detail::parallel_for(nk, 2, work);
  return out;
}

}  // namespace vpm
