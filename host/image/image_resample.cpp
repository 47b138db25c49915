#include <algorithm>
#include <cmath>
#include <vector>

#include "core/parallel.hpp"
#include "vpm/image.hpp"

namespace vpm {

namespace {
float sample(const Image& im, const Eigen::Vector3d& v, Interpolation mode) {
  const auto& d = im.dims;
  if (mode == Interpolation::nearest) {
    const int i = static_cast<int>(std::lround(v.x())), j = static_cast<int>(std::lround(v.y())),
              k = static_cast<int>(std::lround(v.z()));
    if (i < 0 || j < 0 || k < 0 || i >= d[0] || j >= d[1] || k >= d[2]) return 0.0f;
    return im.at(i, j, k);
  }
  const int i0 = static_cast<int>(std::floor(v.x())), j0 = static_cast<int>(std::floor(v.y())),
            k0 = static_cast<int>(std::floor(v.z()));
  const double fx = v.x() - i0, fy = v.y() - j0, fz = v.z() - k0;
  double acc = 0;
  for (int c = 0; c < 8; ++c) {
    const int i = i0 + (c & 1), j = j0 + ((c >> 1) & 1), k = k0 + ((c >> 2) & 1);
    if (i < 0 || j < 0 || k < 0 || i >= d[0] || j >= d[1] || k >= d[2]) continue;
    const double w = ((c & 1) ? fx : 1 - fx) * (((c >> 1) & 1) ? fy : 1 - fy) * (((c >> 2) & 1) ? fz : 1 - fz);
    acc += w * im.at(i, j, k);
  }
  return static_cast<float>(acc);
}
}  // namespace

float sample_image(const Image& image, const Eigen::Vector3d& x, Interpolation interpolation) {
  return sample(image, image.to_voxel(x), interpolation);
}

bool inside_grid(const Image& image, const Eigen::Vector3d& x) {
  const Eigen::Vector3d v = image.to_voxel(x);
  for (int c = 0; c < 3; ++c)
    if (!(v(c) >= -0.5 && v(c) <= image.dims[c] - 0.5)) return false;
  return true;
}

Image resample_image(const Image& image, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& pull,
                     Interpolation interpolation) {
  Image out = image;
  const int nk = image.dims[2];
  auto work = [&](int k_begin, int k_end) {
    for (int k = k_begin; k < k_end; ++k)
      for (int j = 0; j < image.dims[1]; ++j)
        for (int i = 0; i < image.dims[0]; ++i) {
          const Eigen::Vector3d x = image.to_world(Eigen::Vector3d(i, j, k));
          out.data[image.index(i, j, k)] = sample(image, image.to_voxel(pull(x)), interpolation);
        }
  };
  detail::parallel_for(nk, 2, work);
  return out;
}

}  // namespace vpm
