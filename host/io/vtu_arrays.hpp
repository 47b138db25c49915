#pragma once
// Private: the DataArrays of a .vtu being read (vtu.cpp): one array's attributes and values,
// ASCII or binary (io/vtk_binary.hpp); appended arrays get their values when <AppendedData> is read.
#include <string>
#include <string_view>
#include <vector>

#include "io/vtk_binary.hpp"
#include "io/xml.hpp"

namespace vpm::detail {

struct VtuArray {
  std::string name, type;
  int comps = 1;
  std::vector<double> values;
  size_t line = 1;
  long long appended_offset = -1;  ///< format="appended": where its blob starts; values come later
  long long rows = -1;             ///< tuples expected (-1: any, for connectivity)
};

bool is_integer_type(const std::string& type);

/// The non-negative integer attribute `key` of `tag` (or `fallback` when absent and not required).
long long attr_count(const XmlWalker& w, const Tag& tag, const std::string& key, bool required, long long fallback);

/// Position of the "</DataArray" closing `tag`; `label` names the array in the message if absent.
size_t array_close(const XmlWalker& w, const Tag& tag, const std::string& label);

/// A DataArray's text: up to its first child element (VTK 9 puts <InformationKey> elements after
/// the values of Points) or its closing tag at `close`.
std::string_view array_text(const XmlWalker& w, const Tag& tag, size_t close);

/// Binary values into `a` (a.rows >= 0: exactly that many tuples).
void set_binary_values(const XmlWalker& w, VtuArray& a, const std::vector<unsigned char>& bytes);

/// ASCII text cut at whitespace into pieces (for the host threads): piece j is
/// [cut[j], cut[j+1]) and holds the tokens first[j] .. first[j+1]-1 (tokens: runs of
/// non-whitespace, as Scanner without comments reads them).
struct AsciiPieces {
  std::vector<size_t> cut;
  std::vector<long long> first;
  int pieces() const { return static_cast<int>(cut.size()) - 1; }
  long long total() const { return first.back(); }
};
AsciiPieces ascii_pieces(std::string_view text);

/// Reads a DataArray: exactly `rows` tuples of its components (rows < 0: any number, binary forms
/// only). ASCII and inline binary now; an appended array gets its offset and no values yet.
/// `pieces`: the ASCII text's ascii_pieces when the caller has them (counting its tokens).
VtuArray read_array(const std::string& path, XmlWalker& w, const Tag& tag, long long rows, const VtkBinaryLayout& layout,
                    const char* unnamed = "(unnamed)", const AsciiPieces* pieces = nullptr);

}  // namespace vpm::detail
