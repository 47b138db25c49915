#pragma once
// Private: a digest line at the start of a binary file (in HDF5's user block, which the library
// skips): "vpm hdf5 crc32 XXXXXXXX\n", the CRC-32 (zlib's) of every byte after the first
// `header` bytes. A reader checks it before a parser that is not written to survive malformed
// input (libhdf5) reads anything, so a truncated or corrupted file is refused with one message.
// It detects accidents, not forgeries: a file crafted with a matching digest passes.
#include <cstddef>
#include <string>

namespace vpm::detail {

/// The digest line of the `size` bytes at `data` (what follows the header).
std::string digest_line(const char* data, std::size_t size);

/// InputError "PATH: <missing>" when the file at `path` does not start with a digest line, and
/// "PATH: its contents do not match their digest (a truncated or corrupt file)" when the bytes
/// after its first `header` bytes do not match it.
void check_digest(const std::string& path, std::size_t header, const std::string& missing);

}  // namespace vpm::detail
