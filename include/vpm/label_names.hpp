#pragma once
// Region names of a label image (atlas or segmentation), read from the text tables neuroimaging
// tools ship with them. Two formats, told apart line by line:
//
//  * AAL's (mricron's aal.nii.txt): "id name" or "id name code", e.g. "71 Caudate_L 7001";
//  * FreeSurfer's colour table (FreeSurferColorLUT.txt, also fMRIPrep's and FSL's LUTs):
//    "id name R G B A" with the colour as four integers 0-255, e.g.
//    "17  Left-Hippocampus  220 216 20 0".
//
// Blank lines and lines whose first non-blank character is '#' are skipped.
#include <array>
#include <map>
#include <string>

namespace vpm {

struct LabelTable {
  std::map<int, std::string> names;              ///< label id -> region name
  std::map<int, std::array<int, 4>> colours;     ///< label id -> R, G, B, A (colour tables only)
  std::string format;                            ///< "aal" or "freesurfer"
};

/// Reads a label table in either format. Throws InputError("PATH:LINE: what") for a line that is
/// neither (an id that is not an integer, a missing name, colour values outside 0-255, a line
/// with a colour in a file whose other lines have none or the reverse), a label listed twice,
/// or a file that cannot be read or holds no label.
LabelTable read_label_table(const std::string& path);

/// The names of read_label_table(path).
std::map<int, std::string> read_label_names(const std::string& path);

}  // namespace vpm
