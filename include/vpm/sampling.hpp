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

/// The file format of a subject table, chosen by its name.
enum class TableFormat {
  /// .h5 (or .hdf5), what `vpm sample` writes by default: HDF5 readable without vpm (h5py,
  /// MATLAB, nibabel's users), values as float32, chunked and compressed. Root attributes
  /// "format" ("vpm element table"), "format_version" (1), "metadata" (the JSON object of the TSV
  /// sidecar below), "subject", "level", "shells", "samples", "layout"; datasets
  /// /features/<name>/mean and /std (float32, one value per element), /features/<name>/count
  /// (uint16), and per label image k /labels/<k>/ids (int32, L) and /labels/<k>/fraction
  /// (float32, L x elements). The standard deviations keep 12 significant bits (relative 1/4096;
/// the spread of a few samples is uncertain by far more), the rest full float32. Level-6 tables
/// of two features take about 20 MB (docs/collective.md).
  hdf5,
  /// .tsv: one row per element (element, shell, triangle, samples, then <name>_mean, <name>_std,
  /// <name>_count per feature, then label_<id> fractions), ten significant digits, with a JSON
  /// sidecar (sidecar_path) holding the definition, subject, mesh, features with their sources,
  /// label sources and the columns' descriptions. An export for spreadsheets and scripts.
  tsv,
};
/// The format of the table at `path` by its extension; InputError naming it for any other.
TableFormat table_format(const std::string& path);

/// Writes `table` in the format its path names (table_format). Atomic: nothing is left under any
/// name when writing fails; InputError naming the path when it cannot be written or a column's
/// length differs from the definition's element count.
void write_subject_table(const std::string& path, const ElementTable& table);

/// Reads a subject table written by write_subject_table, in the format its path names. Throws
/// InputError naming the file and the place (line, or HDF5 object) when a column, a row, a
/// dataset or the metadata is missing or malformed, when the values do not match the element
/// definition, or when the file is truncated or corrupt.
ElementTable read_subject_table(const std::string& path);

/// The columns a reader needs: a reference reads one or two features' means and counts of many
/// tables, not every column.
struct TableColumns {
  std::vector<std::string> features;  ///< features to read (empty: all); absent ones are skipped
  bool spread = true;                 ///< the features' std (else left empty)
  bool labels = true;                 ///< label fractions (else none)
};
/// As read_subject_table, only `columns` (an HDF5 table reads nothing else from disk).
ElementTable read_subject_table(const std::string& path, const TableColumns& columns);

}  // namespace vpm
