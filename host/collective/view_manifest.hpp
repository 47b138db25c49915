#pragma once
// The page's manifest and data chunks (format vpm-view-2, docs/view.md) from a CohortView: the
// base chunk (display sphere, reference, atlas regions, the normals' mean shape), a chunk per
// group of rows (each subject's shape as 8-bit differences from the mean shape, values and
// patients' z as 16-bit codes, foci per element), a chunk per patient for its detail (element
// centres, slices) and, for a data folder, the normals' values by element (the detail's
// distribution without reading every row).
#include <string>

#include "collective/view_pack.hpp"
#include "vpm/cohort_view.hpp"

namespace vpm::detail {

struct ManifestOptions {
  int rows_per_chunk = 8;
  int column_elements = 1024;
  bool columns = false;  ///< write the normals' values by element (data folders)
  std::string page_dir;  ///< image paths are written relative to it
};

/// The manifest (without "layout", "data_dir", "id"); the chunks go through `pack`.
Json view_manifest(ChunkPack& pack, const CohortView& view, const ManifestOptions& options);

}  // namespace vpm::detail
