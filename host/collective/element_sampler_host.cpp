// ElementSampler's host side (collective/element_sampler_backend.hpp): the elements of a block
// split over the host threads, each element through kernels/element_sampling.clh.
#include <vector>

#include "collective/element_sampler_backend.hpp"
#include "core/parallel.hpp"

namespace vpm::detail {

namespace {

class HostSampler final : public SamplerBackend {
 public:
  HostSampler(const ElementArrays& elements, const SamplerMesh& mesh) : layout_(es_layout(elements)) {
    mesh_.inv = mesh.grid.inv.data();
    mesh_.nbr = mesh.nbr.data();
    mesh_.tets = mesh.tets.data();
    mesh_.native = mesh.native.data();
    mesh_.grid = tl_grid(mesh.grid);
  }

  void set_images(const std::vector<const Image*>& images, int nf) override {
    images_.clear();
    for (const Image* im : images) images_.push_back(ir_image(*im));
    nf_ = nf;
  }

  void run(SampleBlock& b) override {
    const int nf = nf_, nl = static_cast<int>(images_.size()) - nf_, S = layout_.samples;
    parallel_for(b.count, 64, [&](int begin, int end) {
      std::vector<double> acc(3 * static_cast<size_t>(nf) + 1);
      long long st[3] = {0, 0, 0};
      for (int i = begin; i < end; ++i) {
        sp_element(&layout_, &mesh_, images_.data(), nf, nl, b.first + i, acc.data(),
                   b.labels.data() + static_cast<size_t>(i) * nl * S, st);
        for (int f = 0; f < nf; ++f) {
          const size_t o = static_cast<size_t>(f) * b.count + i;
          sp_moments(&acc[3 * static_cast<size_t>(f)], &b.mean[o], &b.std[o]);
          b.in_grid[o] = static_cast<int>(acc[3 * static_cast<size_t>(f) + 2]);
        }
      }
    });
  }

 private:
  EsLayout layout_;
  SpMesh mesh_;
  std::vector<IrImage> images_;
  int nf_ = 0;
};

}  // namespace

std::unique_ptr<SamplerBackend> host_sampler(const ElementArrays& elements, const SamplerMesh& mesh) {
  return std::make_unique<HostSampler>(elements, mesh);
}

}  // namespace vpm::detail
