#pragma once
// Private: a GIfTI file (.gii) as its DataArrays, read with expat (gifti_document.cpp), and the
// values of one array decoded (gifti_decode.cpp). Only the GIfTI DTD's elements, each under the
// parent it gives them, with one <GIFTI> root, are accepted; metadata, label tables and
// coordinate transforms are checked for place and otherwise ignored.
#include <string>
#include <vector>

namespace vpm::detail {

/// Most values vpm reads from one array (a gzip-compressed array can expand a thousandfold):
/// 2^25, 11 million vertices or triangles; a cortical surface has 150,000.
constexpr long long kGiftiMaxValues = 1LL << 25;

/// One <DataArray>: its attributes, checked for form, and its <Data> text, not yet decoded.
struct GiftiArray {
  int index = 0;                ///< position in the file, from 0
  size_t line = 0;              ///< line of its start tag
  std::string intent;           ///< e.g. NIFTI_INTENT_POINTSET
  std::string data_type;        ///< e.g. NIFTI_TYPE_FLOAT32
  std::vector<long long> dims;  ///< Dim0 .. Dim(Dimensionality-1)
  bool column_major = false;    ///< ArrayIndexingOrder="ColumnMajorOrder"
  std::string encoding;         ///< ASCII, Base64Binary, GZipBase64Binary or ExternalFileBinary
  bool big_endian = false;      ///< Endian="BigEndian"
  std::string data;             ///< the <Data> text (character data, CDATA included)

  long long values() const;  ///< product of dims
};

/// The DataArrays of the GIfTI file at `path`. InputError naming the path and line when it is
/// not well-formed XML, not GIfTI's element tree, or an array's attributes are missing or bad.
std::vector<GiftiArray> read_gifti_document(const std::string& path);

/// The values of `a` in row-major order, widened to double. InputError (naming `path` and the
/// array) for external data, more than kGiftiMaxValues values, or data that do not decode to
/// exactly values() of its type.
std::vector<double> gifti_values(const GiftiArray& a, const std::string& path);

}  // namespace vpm::detail
