#pragma once
// Per-element features of one subject (paper 6.2; docs/collective.md): the canonical elements'
// sample points (vpm/elements.hpp) are pulled back from the common ball to the subject's native
// space through its registered ball mesh (containing tet -> barycentric coordinates -> the same
// combination of the vertices' native positions), and the subject's images are read there.
// Every subject gets the same number of samples per element, at the same places of the ball.
// The functions below hold every sample's native position (24 bytes a sample); ElementSampler
// (vpm/element_sampler.hpp) computes the same table without, on the host threads or a GPU.
#include <string>
#include <vector>

#include "vpm/elements.hpp"
#include "vpm/image.hpp"
#include "vpm/json.hpp"
#include "vpm/locate.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

/// Native positions of every element sample (row id * S + s, as CanonicalElements::samples).
/// `ball` (n x 3) the subject's registered ball mesh with `tets` (m x 4), `native` (n x 3) the
/// same vertices in native space (the mesh's `original_position` field). Samples in the thin
/// gap between the inscribed mesh and the sphere use the nearest boundary tet's clamped
/// barycentric coordinates. Runs on the host threads.
Points pull_back_samples(const CanonicalElements& elements, const Points& ball, const Tets& tets, const Points& native);

/// One feature's per-element statistics over the element's samples inside the image grid.
struct ElementFeature {
  std::string name;          ///< column prefix, e.g. "pet"
  std::string source;        ///< the image it was read from
  std::vector<double> mean;  ///< per element (0 when count is 0)
  std::vector<double> std;   ///< population standard deviation per element
  std::vector<int> count;    ///< samples inside the image grid per element
};

/// Per-element fractions of the samples falling on each label of a label image.
struct ElementLabels {
  std::string source;
  std::vector<int> labels;                  ///< the labels present, ascending (0 excluded)
  std::vector<std::vector<double>> fraction;  ///< fraction[l][e] for labels[l], element e
};

/// Everything sampled for one subject: the table `vpm sample` writes.
struct ElementTable {
  ElementDefinition definition;
  std::string subject;  ///< e.g. "sub-01" (free text, recorded in the sidecar)
  std::string mesh;     ///< the registered ball mesh the samples were pulled back through
  std::vector<ElementFeature> features;
  std::vector<ElementLabels> label_images;
};

/// Reads `image` at the native `positions` of the samples (trilinear) and reduces per element.
ElementFeature sample_feature(const CanonicalElements& elements, const Points& positions, const Image& image,
                              const std::string& name);

/// Reads a label image at the samples (nearest voxel) and counts label fractions per element.
ElementLabels sample_label_fractions(const CanonicalElements& elements, const Points& positions, const Image& labels);

/// Writes `table` as TSV (one row per element: element, shell, triangle, samples, then
/// <name>_mean, <name>_std for each feature, then label_<id> fractions) and its JSON sidecar
/// (sidecar_path: definition, subject, mesh, features with sources, label sources, columns).
/// Atomic; InputError naming the path when it cannot be written.
void write_subject_table(const std::string& tsv_path, const ElementTable& table);

/// Reads a subject table written by write_subject_table (the TSV and its JSON sidecar). Throws
/// InputError naming the file and line when a column, a row or the sidecar is missing or
/// malformed, or when the rows do not match the sidecar's element definition.
ElementTable read_subject_table(const std::string& tsv_path);

}  // namespace vpm
