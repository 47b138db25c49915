#pragma once
// Per-element features of one subject, read without holding the element samples (paper 6.2;
// docs/collective.md "Sampling"). Each sample point is made from (element, index) when it is
// needed (CanonicalElements::sample), located in the subject's registered ball mesh, carried to
// native space by the same barycentric combination of the vertices' native positions and read in
// the images there; the per-element statistics are reduced on the spot. Elements go in blocks, so
// the memory is the mesh's, the images' and the table's, never one entry per sample.
//
// The host threads and the OpenCL device run the same arithmetic (kernels/element_sampling.clh
// and the headers it builds on: the sample generator, point location, the image reads); which
// one runs is a placement (vpm/placement.hpp, PlacedWork::sampling), decided once and reported.
//
//   ElementSampler sampler(elements, mesh.vertices, mesh.tets, native, Device::current());
//   ElementTable table = sampler.sample({{"pet", &pet}, {"t1w", &t1w}}, {&labels});
#include <memory>
#include <string>
#include <vector>

#include "vpm/device.hpp"
#include "vpm/elements.hpp"
#include "vpm/image.hpp"
#include "vpm/mesh.hpp"
#include "vpm/placement.hpp"
#include "vpm/sampling.hpp"

namespace vpm {

/// A feature image and the prefix of its columns (NAME_mean, NAME_std, NAME_count).
struct NamedImage {
  std::string name;
  const Image* image = nullptr;  ///< not owned: alive while ElementSampler::sample runs
};

/// Where and in what blocks an ElementSampler works.
struct ElementSamplerOptions {
  ExecutionPlace place = ExecutionPlace::automatic;  ///< host threads or device kernels (place_work)
  /// Elements per block (at least 1): the blocks' results take 20 bytes per element and feature
  /// image and 4 per sample and label image; a block is one kernel launch on a device.
  int block = 1 << 18;
};

/// Reads images at the canonical elements' samples pulled back through one registered ball mesh.
/// The mesh is prepared (and, on a device, uploaded) once; sample() can then read any images.
class ElementSampler {
 public:
  /// `elements` the element set (kept: copies share its generator arrays); `ball` (n x 3) the
  /// subject's registered ball mesh with `tets` (m x 4, non-degenerate); `native` (n x 3) the
  /// same vertices in native space (the mesh's `original_position`). Work runs on `device`'s
  /// kernels or on the host threads as place_work(device, sampling, options.place) decides.
  /// InputError when `native` and `ball` differ in rows, a tet names a missing vertex or there
  /// are no tets.
  ElementSampler(const CanonicalElements& elements, const Points& ball, const Tets& tets, const Points& native,
                 Device& device, const ElementSamplerOptions& options = {});
  ~ElementSampler();
  ElementSampler(ElementSampler&&) noexcept;
  ElementSampler& operator=(ElementSampler&&) noexcept;

  /// The subject's table without subject and mesh: the element definition, one ElementFeature
  /// per entry of `images` (in order: mean, population std and count of the trilinear values at
  /// the samples inside the image grid, as sample_feature) and one ElementLabels per entry of
  /// `labels` (nearest-voxel label fractions, as sample_label_fractions). Equal to
  /// pull_back_samples followed by those two to round-off: the same tets are found (a sample on a
  /// face two tets share may take either, with the same native position to round-off), and on
  /// the host threads the values are theirs bit for bit but for samples in the thin gap outside
  /// the inscribed mesh, whose walk may end in a neighbouring boundary tet. InputError when
  /// there is nothing to read or an image pointer is null.
  ElementTable sample(const std::vector<NamedImage>& images, const std::vector<const Image*>& labels = {}) const;

  /// Where sample() runs (the `sampling` part) and why.
  const Placement& placement() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vpm
