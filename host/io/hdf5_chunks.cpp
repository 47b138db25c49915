// Reading vpm's own datasets chunk by chunk (io/hdf5.hpp, Reader::direct): the library's global
// lock is held only to fetch the compressed chunks; inflating (zlib), unshuffling and converting
// run on the host's threads. Everything a chunk declares is checked before it is used: its stored
// size, the filters applied to it, and that it inflates to exactly one chunk.
#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <exception>

#include "core/parallel.hpp"
#include "io/hdf5.hpp"
#include "io/hdf5_lock.hpp"
#include "vpm/error.hpp"

namespace vpm::detail::h5 {

namespace {

// A chunk as stored, and what the filters skipped for it (filter_mask: bit k, filter k).
struct RawChunk {
  std::vector<unsigned char> bytes;
  unsigned mask = 0;
};

// Whether `dcpl` holds exactly shuffle then deflate.
bool shuffle_deflate(hid_t dcpl) {
  if (H5Pget_nfilters(dcpl) != 2) return false;
  unsigned flags = 0;
  size_t nvalues = 0;
  const H5Z_filter_t first = H5Pget_filter2(dcpl, 0, &flags, &nvalues, nullptr, 0, nullptr, nullptr);
  nvalues = 0;
  const H5Z_filter_t second = H5Pget_filter2(dcpl, 1, &flags, &nvalues, nullptr, 0, nullptr, nullptr);
  return first == H5Z_FILTER_SHUFFLE && second == H5Z_FILTER_DEFLATE;
}

// Chunk `raw` of `bytes` bytes of `size`-byte values turned into the values `out` (count of them).
void decode(const RawChunk& raw, size_t bytes, size_t size, bool is_float, size_t count, double* out,
            std::vector<unsigned char>& inflated, std::vector<unsigned char>& plain) {
  const unsigned char* data = raw.bytes.data();
  if (!(raw.mask & 2u)) {  // deflate applied
    inflated.resize(bytes);
    uLongf length = static_cast<uLongf>(bytes);
    if (uncompress(inflated.data(), &length, raw.bytes.data(), static_cast<uLong>(raw.bytes.size())) != Z_OK ||
        length != bytes)
      throw InputError("a chunk does not inflate to its size");
    data = inflated.data();
  } else if (raw.bytes.size() != bytes) {
    throw InputError("an uncompressed chunk of the wrong size");
  }
  if (!(raw.mask & 1u)) {  // shuffle applied: byte b of value j was stored at b * n + j
    const size_t n = bytes / size;
    plain.resize(bytes);
    for (size_t b = 0; b < size; ++b)
      for (size_t j = 0; j < n; ++j) plain[j * size + b] = data[b * n + j];
    data = plain.data();
  }
  for (size_t j = 0; j < count; ++j) {
    if (is_float) {
      float f;
      std::memcpy(&f, data + j * 4, 4);
      out[j] = f;
    } else {
      std::uint16_t u;
      std::memcpy(&u, data + j * 2, 2);
      out[j] = u;
    }
  }
}

}  // namespace

std::optional<std::vector<double>> Reader::direct(const std::string& path, std::size_t rows, bool integral) const {
  std::vector<RawChunk> raw;
  size_t chunk = 0, size = 0;
  bool is_float = false;
  {
    Guard g;
    Id d = open_dataset(path, rows, 1, integral);  // shape, type class, chunk bounds, every chunk stored
    const hid_t dataset = static_cast<hid_t>(d.get());
    Id dcpl(H5Dget_create_plist(dataset)), type(H5Dget_type(dataset));
    hsize_t dims[1] = {0};
    if (rows == 0 || H5Pget_layout(static_cast<hid_t>(dcpl.get())) != H5D_CHUNKED ||
        H5Pget_chunk(static_cast<hid_t>(dcpl.get()), 1, dims) != 1 || !shuffle_deflate(static_cast<hid_t>(dcpl.get())))
      return std::nullopt;
    is_float = H5Tequal(static_cast<hid_t>(type.get()), H5T_IEEE_F32LE) > 0;
    if (!is_float && H5Tequal(static_cast<hid_t>(type.get()), H5T_STD_U16LE) <= 0) return std::nullopt;
    size = is_float ? 4 : 2;
    chunk = dims[0];
    raw.resize((rows + chunk - 1) / chunk);
    for (size_t i = 0; i < raw.size(); ++i) {
      hsize_t offset[1] = {i * chunk}, stored = 0;
      // deflate's worst case grows a chunk by 0.1 % and a few bytes
      if (H5Dget_chunk_storage_size(dataset, offset, &stored) < 0 || stored == 0 || stored > chunk * size * 2 + 4096)
        throw InputError(path_ + ": " + path + ": chunk " + std::to_string(i) + " is stored with an impossible size");
      raw[i].bytes.resize(stored);
      uint32_t mask = 0;
      if (H5Dread_chunk(dataset, H5P_DEFAULT, offset, &mask, raw[i].bytes.data()) < 0)
        throw InputError(path_ + ": " + path + ": chunk " + std::to_string(i) + " does not read (a corrupt or truncated file)");
      raw[i].mask = mask;
    }
  }
  std::vector<double> out(rows);
  std::vector<std::exception_ptr> errors(raw.size());
  parallel_for(static_cast<int>(raw.size()), 4, [&](int begin, int end) {
    std::vector<unsigned char> inflated, plain;
    for (int i = begin; i < end; ++i) try {
        const size_t first = static_cast<size_t>(i) * chunk;
        decode(raw[static_cast<size_t>(i)], chunk * size, size, is_float, std::min(chunk, rows - first), out.data() + first,
               inflated, plain);
      } catch (const std::exception& e) {
        errors[static_cast<size_t>(i)] =
            std::make_exception_ptr(InputError(path_ + ": " + path + ": chunk " + std::to_string(i) + ": " + e.what()));
      }
  });
  for (const std::exception_ptr& x : errors)
    if (x) std::rethrow_exception(x);
  return out;
}

}  // namespace vpm::detail::h5
