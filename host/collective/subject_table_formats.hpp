#pragma once
// Private: the two file formats of a subject table (vpm/sampling.hpp). HDF5 (.h5) is what
// `vpm sample` writes by default: float32 values, chunked and compressed, the metadata as
// attributes; TSV (.tsv, with a JSON sidecar) is the text export. Both carry the same metadata
// object (table_metadata), so a table converts between them without loss but the values'
// precision.
#include <string>

#include "vpm/json.hpp"
#include "vpm/sampling.hpp"

namespace vpm::detail {

/// The metadata of `table`: {definition, elements, subject, mesh, features: [{name, source,
/// interpolation}], label_images: [{source, labels}], columns} (the TSV's sidecar, the HDF5
/// file's "metadata" attribute).
Json table_metadata(const ElementTable& table);

/// Reads the metadata written by table_metadata into `table`: its definition, subject, mesh,
/// and with `with_features` one ElementFeature (name and source, no values) per entry of
/// "features" (else only the sources of the features already in `table`, by position).
/// InputError naming `source` when a field is missing or malformed.
void read_table_metadata(const Json& metadata, const std::string& source, ElementTable& table, bool with_features);

void write_subject_table_tsv(const std::string& path, const ElementTable& table);
ElementTable read_subject_table_tsv(const std::string& path);

void write_subject_table_hdf5(const std::string& path, const ElementTable& table);
ElementTable read_subject_table_hdf5(const std::string& path, const TableColumns& columns);

/// The element count of `table`'s definition, after checking that every feature and label
/// column has that many values (InputError naming `path` otherwise).
int checked_table_size(const std::string& path, const ElementTable& table);

}  // namespace vpm::detail
