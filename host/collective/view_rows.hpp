#pragma once
// The subjects' chunks of the page's data (collective/view_manifest.hpp): rows, details, columns.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "collective/view_manifest.hpp"

namespace vpm::detail {

/// Every subject's centre (the mean of its outer shell's display vertices), the normals' mean
/// shape about their centres (shells x vertices x 3, mm) and per shell the largest distance of a
/// subject's surface from its centre (the page scales shell k by it).
struct Shapes {
  std::vector<std::array<double, 3>> centre;
  std::vector<float> mean;
  std::vector<double> shell_radius;
};
Shapes subject_shapes(const CohortView& view);

/// The 16-bit codes per feature of values (every subject) and z (patients).
struct FeatureCodes {
  std::map<std::string, Quantiser> values, z;
};

/// First element id of each shell, and the element count last.
std::vector<long> shell_offsets(const ElementDefinition& definition);

/// The subjects' entries of the manifest; their rows (rows_per_chunk subjects a chunk, in order)
/// and each patient's detail chunk go through `pack`.
Json subject_chunks(ChunkPack& pack, const CohortView& view, const Shapes& shapes, const FeatureCodes& codes,
                    const ManifestOptions& options);

/// The normals' values by element (`elements` elements a chunk, each element's normals in a row):
/// the manifest's "columns".
Json column_chunks(ChunkPack& pack, const CohortView& view, const FeatureCodes& codes, int elements);

}  // namespace vpm::detail
