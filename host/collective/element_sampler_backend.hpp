#pragma once
// Private: the two sides of vpm::ElementSampler (vpm/element_sampler.hpp). Both run one block of
// elements at a time through kernels/element_sampling.clh: the host on its threads
// (element_sampler_host.cpp), the device in kernels/sampling.cl (element_sampler_device.cpp).
#include <memory>
#include <vector>

#include "collective/element_arrays.hpp"
#include "image/image_read.hpp"
#include "mesh/tet_grid.hpp"
#include "vpm/device.hpp"
#include "vpm/image.hpp"

namespace vpm::detail {

#include "kernels/element_sampling.clh"

/// The registered ball mesh prepared for point location, and its native positions.
struct SamplerMesh {
  Tets tets;
  Points native;                ///< n x 3
  std::vector<int> nbr;         ///< tet_neighbors(tets)
  TetGrid grid;                 ///< over the ball positions, pointing into tets and nbr
};

/// One block's results: elements first .. first + count - 1, nf feature and nl label images.
struct SampleBlock {
  int first = 0, count = 0;
  std::vector<double> mean, std;  ///< [f * count + i]
  std::vector<int> in_grid;       ///< [f * count + i]
  std::vector<int> labels;        ///< [(i * nl + l) * S + s]
};

/// One side: set_images once per ElementSampler::sample, then run per block.
class SamplerBackend {
 public:
  virtual ~SamplerBackend() = default;
  /// The images of the next blocks: `nf` feature images, then the label images.
  virtual void set_images(const std::vector<const Image*>& images, int nf) = 0;
  /// Fills b (b.first, b.count set; its vectors sized by the caller).
  virtual void run(SampleBlock& b) = 0;
};

/// The host's threads over the element arrays and the mesh (both kept by the caller).
std::unique_ptr<SamplerBackend> host_sampler(const ElementArrays& elements, const SamplerMesh& mesh);

/// The kernels of `device` (an OpenCL device): the element arrays and the mesh are uploaded here,
/// blocks of up to `max_block` elements.
std::unique_ptr<SamplerBackend> device_sampler(Device& device, const ElementArrays& elements, const SamplerMesh& mesh,
                                               int max_block);

}  // namespace vpm::detail
