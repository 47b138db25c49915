// vpm::ElementSampler (vpm/element_sampler.hpp): the mesh prepared once, then each sample() runs
// the elements block by block on the side placement chose (collective/element_sampler_backend.hpp)
// and gathers the blocks' statistics and label fractions into the table.
#include "vpm/element_sampler.hpp"

#include <algorithm>
#include <map>
#include <string>

#include "collective/element_sampler_backend.hpp"
#include "vpm/error.hpp"

namespace vpm {

namespace {

// The label columns of one label image, each made (all elements, 0) when its label first occurs.
struct LabelColumns {
  std::map<int, std::vector<double>> column;
  int last = 0;
  std::vector<double>* last_column = nullptr;

  std::vector<double>& of(int label, int elements) {
    if (label == last && last_column) return *last_column;
    std::vector<double>& c = column[label];
    if (c.empty()) c.assign(static_cast<size_t>(elements), 0.0);
    last = label;
    last_column = &c;
    return c;
  }
};

}  // namespace

struct ElementSampler::Impl {
  CanonicalElements elements;
  detail::SamplerMesh mesh;
  Placement placement;
  std::unique_ptr<detail::SamplerBackend> backend;
  int block;

  Impl(const CanonicalElements& el, const Points& ball, const Tets& tets, const Points& native, Device& device,
       const ElementSamplerOptions& options)
      : elements(el), block(std::max(1, options.block)) {
    if (ball.rows() != native.rows())
      throw InputError("sampling: the ball mesh has " + std::to_string(ball.rows()) +
                       " vertices but its native positions " + std::to_string(native.rows()));
    if (tets.size() > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= ball.rows()))
      throw InputError("sampling: the mesh's tets use vertex " + std::to_string(tets.maxCoeff()) + " of " +
                       std::to_string(ball.rows()));
    if (tets.rows() == 0) throw InputError("sampling: the ball mesh has no tets");
    mesh.tets = tets;
    mesh.native = native;
    mesh.nbr = detail::tet_neighbors(mesh.tets);
    detail::build_background(mesh.grid, ball, mesh.tets, mesh.nbr);
    detail::element_directions(el.arrays());  // the backends read the directions table
    const long long samples = static_cast<long long>(el.size()) * el.definition().samples;
    if (placement.decide(device, PlacedWork::sampling, options.place, samples))
      backend = detail::device_sampler(device, el.arrays(), mesh, block);
    else
      backend = detail::host_sampler(el.arrays(), mesh);
  }

  void gather(const detail::SampleBlock& b, ElementTable& t, std::vector<LabelColumns>& labels) const;
};

void ElementSampler::Impl::gather(const detail::SampleBlock& b, ElementTable& t,
                                  std::vector<LabelColumns>& labels) const {
  for (size_t f = 0; f < t.features.size(); ++f) {
    ElementFeature& out = t.features[f];
    const size_t o = f * b.count;
    std::copy(b.mean.begin() + o, b.mean.begin() + o + b.count, out.mean.begin() + b.first);
    std::copy(b.std.begin() + o, b.std.begin() + o + b.count, out.std.begin() + b.first);
    std::copy(b.in_grid.begin() + o, b.in_grid.begin() + o + b.count, out.count.begin() + b.first);
  }
  const int S = elements.definition().samples, nl = static_cast<int>(labels.size()), n = elements.size();
  for (int i = 0; i < b.count; ++i)
    for (int l = 0; l < nl; ++l)
      for (int s = 0; s < S; ++s) {
        const int label = b.labels[(static_cast<size_t>(i) * nl + l) * S + s];
        if (label != 0) labels[l].of(label, n)[b.first + i] += 1.0 / S;
      }
}

ElementSampler::ElementSampler(const CanonicalElements& elements, const Points& ball, const Tets& tets,
                               const Points& native, Device& device, const ElementSamplerOptions& options)
    : impl_(std::make_unique<Impl>(elements, ball, tets, native, device, options)) {}
ElementSampler::~ElementSampler() = default;
ElementSampler::ElementSampler(ElementSampler&&) noexcept = default;
ElementSampler& ElementSampler::operator=(ElementSampler&&) noexcept = default;

const Placement& ElementSampler::placement() const { return impl_->placement; }

ElementTable ElementSampler::sample(const std::vector<NamedImage>& images, const std::vector<const Image*>& labels) const {
  if (images.empty() && labels.empty()) throw InputError("sampling: no image to read");
  std::vector<const Image*> all;
  ElementTable t;
  t.definition = impl_->elements.definition();
  const int n = impl_->elements.size(), S = t.definition.samples;
  for (const NamedImage& im : images) {
    if (!im.image) throw InputError("sampling: feature " + im.name + " has no image");
    all.push_back(im.image);
    ElementFeature f;
    f.name = im.name;
    f.source = im.image->path;
    f.mean.assign(n, 0.0);
    f.std.assign(n, 0.0);
    f.count.assign(n, 0);
    t.features.push_back(std::move(f));
  }
  for (const Image* im : labels) {
    if (!im) throw InputError("sampling: a label image is missing");
    all.push_back(im);
  }
  const int nf = static_cast<int>(images.size()), nl = static_cast<int>(labels.size());
  impl_->backend->set_images(all, nf);
  std::vector<LabelColumns> columns(labels.size());
  detail::SampleBlock b;
  const int block = impl_->block;
  for (int first = 0; first < n; first += block) {
    b.first = first;
    b.count = std::min(block, n - first);
    b.mean.resize(static_cast<size_t>(b.count) * nf);
    b.std.resize(b.mean.size());
    b.in_grid.resize(b.mean.size());
    b.labels.resize(static_cast<size_t>(b.count) * nl * S);
    impl_->backend->run(b);
    impl_->gather(b, t, columns);
  }
  for (size_t l = 0; l < labels.size(); ++l) {
    ElementLabels out;
    out.source = labels[l]->path;
    for (auto& [label, column] : columns[l].column) {
      out.labels.push_back(label);
      out.fraction.push_back(std::move(column));
    }
    t.label_images.push_back(std::move(out));
  }
  return t;
}

}  // namespace vpm
