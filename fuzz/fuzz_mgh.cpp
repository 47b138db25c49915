// Fuzz target for the FreeSurfer MGH reader (read_mgh): the bytes as input.mgh, or as input.mgz
// when they start with the gzip magic. An image that reads holds one value per voxel and a
// finite, invertible affine.
#include <cmath>

#include "fuzz_target.hpp"
#include "vpm/image.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  const bool gz = size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
  const std::string path = fuzz::write_scratch(gz ? "input.mgz" : "input.mgh", fuzz::bytes(data, size));
  fuzz::expect_input_error_only([&] {
    const Image image = read_mgh(path);
    fuzz::require(image.dims[0] > 0 && image.dims[1] > 0 && image.dims[2] > 0, "positive dimensions");
    fuzz::require(image.data.size() == image.size(), "one value per voxel");
    fuzz::require(image.affine.allFinite() && std::abs(image.affine.topLeftCorner<3, 3>().determinant()) > 0,
                  "a finite, invertible affine");
  });
  return 0;
}
