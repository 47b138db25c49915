#pragma once
// Private: the binary data of VTK XML files (.vtu) as VTK and ParaView write them: a DataArray
// with format="binary" (base64 inline) or format="appended" (in <AppendedData>, raw or base64),
// each blob led by a header of UInt32 or UInt64 (VTKFile header_type): the byte count, or with
// compressor="vtkZLibDataCompressor" [blocks, block size, last block size, compressed sizes...]
// and the zlib blocks. In base64 VTK encodes a compressed blob's header apart from its data and
// an uncompressed one's either way; both are accepted. Little-endian data only.
#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace vpm::detail {

struct VtkBinaryLayout {
  int header_bytes = 4;  ///< 4 (UInt32) or 8 (UInt64)
  bool zlib = false;     ///< vtkZLibDataCompressor
  bool big_endian = false;  ///< byte_order="BigEndian": refused
};

/// Called with a message when the data are malformed; does not return (throws).
using VtkBinaryFail = std::function<void(const std::string&)>;

/// Base64 text of `bytes` (RFC 4648, padded, one line).
std::string encode_base64(std::string_view bytes);

/// Bytes of base64 text (whitespace skipped); fails on other characters or a bad length.
std::vector<unsigned char> decode_base64(std::string_view text, const VtkBinaryFail& fail);

/// One blob (header + data) read from raw bytes starting at `p` (`avail` bytes there): the
/// uncompressed data. `used` receives the blob's length in bytes.
std::vector<unsigned char> vtk_raw_blob(const unsigned char* p, size_t avail, const VtkBinaryLayout& layout,
                                        size_t& used, const VtkBinaryFail& fail);

/// One blob in base64 text (inline binary, or an appended array's stretch of base64 text).
std::vector<unsigned char> vtk_base64_blob(std::string_view text, const VtkBinaryLayout& layout, const VtkBinaryFail& fail);

/// Size in bytes of the VTK scalar type `type` (Int8 .. Float64), 0 when unknown.
int vtk_type_size(const std::string& type);

/// The values of `bytes` read as little-endian `type`, widened to double. Fails when the byte
/// count is not a multiple of the type's size.
std::vector<double> vtk_values(const std::vector<unsigned char>& bytes, const std::string& type, const VtkBinaryFail& fail);

}  // namespace vpm::detail
