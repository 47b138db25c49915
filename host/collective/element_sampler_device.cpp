// ElementSampler's device side (collective/element_sampler_backend.hpp): the element arrays,
// the mesh and the images uploaded once, then kernels/sampling.cl's `sample_elements` a work
// item per element of each block, the block's statistics and labels read back.
#include <boost/compute/algorithm/copy.hpp>
#include <boost/compute/container/vector.hpp>
#include <algorithm>
#include <string>
#include <vector>

#include "collective/element_sampler_backend.hpp"
#include "core/device_alloc.hpp"
#include "core/device_cl.hpp"

namespace vpm::detail {

namespace bc = boost::compute;

namespace {

template <class T>
bc::vector<T> upload(Device& d, const T* p, size_t n) {
  static const T none{};
  return n ? bc::vector<T>(p, p + n, d.cl().queue) : bc::vector<T>(&none, &none + 1, d.cl().queue);
}

class DeviceSampler final : public SamplerBackend {
 public:
  DeviceSampler(Device& d, const ElementArrays& el, const SamplerMesh& mesh, int max_block)
      : dev_(d), samples_(el.samples), shells_(static_cast<int>(el.level.size())), max_block_(max_block) {
    const TetGrid& g = mesh.grid;
    const unsigned long long bytes =
        8ULL * (el.corners.size() + el.radius.size() + el.directions.size() + g.inv.size() + mesh.native.size()) +
                                     4ULL * (2 * mesh.tets.size() + g.cell_start.size() + g.cell_tets.size());
    const unsigned long long largest = 8ULL * std::max(el.directions.size(), g.inv.size());
    allocate_on_device(d, "sampling: the elements and the mesh", largest, bytes, [&] {
      offset_ = upload(d, el.offset.data(), el.offset.size());
      u_ = upload(d, el.u.data(), el.u.size());
      radius_ = upload(d, el.radius.data(), el.radius.size());
      dir_ = upload(d, el.directions.data(), el.directions.size());
      level_ = upload(d, el.level.data(), el.level.size());
      first_ = upload(d, el.first.data(), el.first.size());
      corners_ = upload(d, el.corners.data(), el.corners.size());
      inv_ = upload(d, g.inv.data(), g.inv.size());
      nbr_ = upload(d, mesh.nbr.data(), mesh.nbr.size());
      tets_ = upload(d, mesh.tets.data(), static_cast<size_t>(mesh.tets.size()));
      native_ = upload(d, mesh.native.data(), static_cast<size_t>(mesh.native.size()));
      cell_start_ = upload(d, g.cell_start.data(), g.cell_start.size());
      cell_tets_ = upload(d, g.cell_tets.data(), g.cell_tets.size());
    });
    for (int c = 0; c < 3; ++c) {
      lo_[c] = g.lo[c];
      dims_[c] = g.dims[c];
    }
    inv_h_ = g.inv_h;
  }

  void set_images(const std::vector<const Image*>& images, int nf) override;
  void run(SampleBlock& b) override;

 private:
  Device& dev_;
  int samples_, shells_, max_block_, nf_ = 0, nl_ = 0;
  double lo_[3] = {0, 0, 0}, inv_h_ = 1;
  int dims_[3] = {1, 1, 1};
  bc::kernel kernel_;
  bc::vector<int> offset_, level_, first_, nbr_, tets_, cell_start_, cell_tets_, dims_img_, in_grid_, labels_;
  bc::vector<double> corners_, u_, radius_, dir_, inv_, native_, affine_, mean_, std_;
  bc::vector<cl_long> voxel_offset_;
  bc::vector<float> voxels_;
};

void DeviceSampler::set_images(const std::vector<const Image*>& images, int nf) {
  nf_ = nf;
  nl_ = static_cast<int>(images.size()) - nf;
  std::vector<double> affine;
  std::vector<int> dims;
  std::vector<cl_long> offset;
  size_t voxels = 0;
  for (const Image* im : images) {
    const IrImage r = ir_image(*im);
    affine.insert(affine.end(), r.inv, r.inv + 9);
    affine.insert(affine.end(), r.t, r.t + 3);
    dims.insert(dims.end(), r.dims, r.dims + 3);
    offset.push_back(static_cast<cl_long>(voxels));
    voxels += im->data.size();
  }
  const size_t block = static_cast<size_t>(max_block_);
  const size_t out = block * static_cast<size_t>(nf), lab = block * static_cast<size_t>(nl_) * samples_;
  auto& q = dev_.cl().queue;
  voxels_ = bc::vector<float>(dev_.cl().context);  // the last images' go first
  allocate_on_device(dev_, "sampling: the images", 4ULL * voxels, 4ULL * voxels + 20ULL * out + 4ULL * lab, [&] {
    voxels_ = bc::vector<float>(voxels, dev_.cl().context);
    for (size_t k = 0; k < images.size(); ++k)
      if (!images[k]->data.empty())
        q.enqueue_write_buffer(voxels_.get_buffer(), 4 * static_cast<size_t>(offset[k]), 4 * images[k]->data.size(),
                               images[k]->data.data());
    mean_ = bc::vector<double>(std::max<size_t>(out, 1), dev_.cl().context);
    std_ = bc::vector<double>(std::max<size_t>(out, 1), dev_.cl().context);
    in_grid_ = bc::vector<int>(std::max<size_t>(out, 1), dev_.cl().context);
    labels_ = bc::vector<int>(std::max<size_t>(lab, 1), dev_.cl().context);
  });
  affine_ = upload(dev_, affine.data(), affine.size());
  dims_img_ = upload(dev_, dims.data(), dims.size());
  voxel_offset_ = upload(dev_, offset.data(), offset.size());
  kernel_ = dev_.cl().kernel("sampling", "sample_elements",
                             "-DSP_FEATURES=" + std::to_string(nf_) + " -DSP_LABELS=" + std::to_string(nl_));
  kernel_.set_args(0, 0, shells_, samples_, offset_, level_, first_, corners_, u_, radius_, dir_, inv_, nbr_, tets_, native_,
                   lo_[0], lo_[1], lo_[2], inv_h_, dims_[0], dims_[1], dims_[2], cell_start_, cell_tets_, affine_,
                   dims_img_, voxel_offset_, voxels_, mean_, std_, in_grid_, labels_);
}

void DeviceSampler::run(SampleBlock& b) {
  auto& q = dev_.cl().queue;
  set_args_at(kernel_, 0, b.first, b.count);
  dev_.cl().launch(kernel_, static_cast<size_t>(b.count));
  const size_t out = static_cast<size_t>(b.count) * nf_, lab = static_cast<size_t>(b.count) * nl_ * samples_;
  if (out) {
    bc::copy(mean_.begin(), mean_.begin() + out, b.mean.begin(), q);
    bc::copy(std_.begin(), std_.begin() + out, b.std.begin(), q);
    bc::copy(in_grid_.begin(), in_grid_.begin() + out, b.in_grid.begin(), q);
  }
  if (lab) bc::copy(labels_.begin(), labels_.begin() + lab, b.labels.begin(), q);
}

}  // namespace

std::unique_ptr<SamplerBackend> device_sampler(Device& device, const ElementArrays& elements, const SamplerMesh& mesh,
                                               int max_block) {
  return std::make_unique<DeviceSampler>(device, elements, mesh, max_block);
}

}  // namespace vpm::detail
