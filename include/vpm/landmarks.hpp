#pragma once
// Landmark files: the CSV format `vpm register` reads (--landmarks, --targets) and `vpm demo`
// writes. One landmark a line, in ball coordinates or as a vertex id of the mapped mesh.
#include <string>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm {

/// Landmarks read from a CSV file.
struct LandmarkFile {
  Points points;           ///< N x 3 ball coordinates
  std::vector<int> lines;  ///< 1-based line of each landmark in the file
};

/// Reads a landmark CSV: one landmark a line, either `x,y,z` (ball coordinates) or a single
/// `vertex_id` (0-based row of `vertices`, n x 3, whose position is used). Blank lines and
/// lines starting with '#' are skipped; a first line that is not numeric is a header.
/// Separators: commas (spaces and tabs around values are ignored; CRLF accepted).
/// Throws InputError("FILE:LINE: what") on malformed lines, ids out of range, an empty file,
/// and ("FILE:LINE: ... outside the unit ball") for points with |p| > 1 + 1e-9.
LandmarkFile read_landmarks_csv(const std::string& path, const Points& vertices);

/// Writes `points` (N x 3 ball coordinates) as a landmark CSV that read_landmarks_csv reads
/// back exactly: header `x,y,z`, then one `x,y,z` line per point (shortest round-trip decimals).
/// Written to a temporary name and renamed; InputError when it cannot write.
void write_landmarks_csv(const std::string& path, const Points& points);

}  // namespace vpm
