// The values of a GIfTI DataArray: ASCII numbers, base64 of the raw bytes, or base64 of their
// zlib (or gzip) stream, either byte order, either index order, widened to double in row-major
// order. Sizes are checked before anything is allocated.
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "io/vtk_binary.hpp"
#include "vpm/error.hpp"
#include "with_gifti/gifti_document.hpp"

namespace vpm::detail {

namespace {

// NIFTI_TYPE_FLOAT32 -> Float32, the type names of io/vtk_binary.
std::string vtk_type(const std::string& gifti_type) {
  std::string t = gifti_type.substr(std::string("NIFTI_TYPE_").size());
  const bool u = t[0] == 'U';
  std::string base = t.substr(u ? 4 : (t[0] == 'I' ? 3 : 5));  // bits
  std::string kind = u ? "UInt" : (t[0] == 'I' ? "Int" : "Float");
  return kind + base;
}

std::vector<double> ascii_values(const GiftiArray& a, const std::string& where) {
  const long long n = a.values();
  std::vector<double> v;
  v.reserve(static_cast<size_t>(n));
  const bool integral = a.data_type.find("FLOAT") == std::string::npos;
  const char* p = a.data.c_str();
  while (true) {
    while (*p == ' ' || *p == '\n' || *p == '\r' || *p == '\t') ++p;
    if (!*p) break;
    char* end = nullptr;
    const double x = std::strtod(p, &end);
    if (end == p) throw InputError(where + "'" + std::string(p, std::min<size_t>(std::strlen(p), 20)) + "' is not a number");
    if (static_cast<long long>(v.size()) == n) throw InputError(where + "more than " + std::to_string(n) + " ASCII values");
    if (integral && x != std::floor(x)) throw InputError(where + "value " + std::string(p, static_cast<size_t>(end - p)) + " is not a whole number");
    v.push_back(x);
    p = end;
  }
  if (static_cast<long long>(v.size()) != n)
    throw InputError(where + std::to_string(v.size()) + " ASCII values; its dimensions give " + std::to_string(n));
  return v;
}

std::vector<unsigned char> inflate_exactly(const std::vector<unsigned char>& in, size_t bytes, const std::string& where) {
  // zlib cannot expand by more than about 1032x: a larger claim is a corrupt header, not memory to reserve
  if (bytes > 1100 * in.size() + 64) throw InputError(where + "compressed data too short for its dimensions");
  std::vector<unsigned char> out(bytes + 1);  // one spare byte: more output than expected is detected
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) throw std::bad_alloc();  // 15 + 32: zlib or gzip header
  z.next_in = const_cast<unsigned char*>(in.data());
  z.avail_in = static_cast<uInt>(in.size());
  z.next_out = out.data();
  z.avail_out = static_cast<uInt>(out.size());
  const int rc = inflate(&z, Z_FINISH);
  const size_t got = z.total_out;
  inflateEnd(&z);
  if (rc != Z_STREAM_END || got != bytes)
    throw InputError(where + "compressed data do not inflate to " + std::to_string(bytes) + " bytes" +
                     (rc == Z_STREAM_END ? " (" + std::to_string(got) + ")" : " (corrupt or truncated)"));
  out.resize(bytes);
  return out;
}

// Row-major order of values stored column-major with dimensions `dims`.
std::vector<double> to_row_major(const std::vector<double>& v, const std::vector<long long>& dims) {
  std::vector<double> out(v.size());
  std::vector<long long> idx(dims.size(), 0);
  for (size_t i = 0; i < v.size(); ++i) {  // i walks row-major; idx is its multi-index
    long long col = 0, stride = 1;
    for (size_t k = 0; k < dims.size(); ++k) {
      col += idx[k] * stride;
      stride *= dims[k];
    }
    out[i] = v[static_cast<size_t>(col)];
    for (size_t k = dims.size(); k-- > 0;)
      if (++idx[k] < dims[k]) break;
      else idx[k] = 0;
  }
  return out;
}

}  // namespace

std::vector<double> gifti_values(const GiftiArray& a, const std::string& path) {
  const std::string where = path + ": DataArray " + std::to_string(a.index) + ": ";
  if (a.encoding == "ExternalFileBinary")
    throw InputError(where + "its data is in an external file, which vpm does not read; write it inline");
  const long long n = a.values();
  if (n > kGiftiMaxValues)
    throw InputError(where + std::to_string(n) + " values: more than vpm reads (" + std::to_string(kGiftiMaxValues) + ")");
  std::vector<double> v;
  if (a.encoding == "ASCII") {
    v = ascii_values(a, where);
  } else {
    const std::string type = vtk_type(a.data_type);
    const size_t size = static_cast<size_t>(vtk_type_size(type));
    const VtkBinaryFail fail = [&](const std::string& what) { throw InputError(where + what); };
    std::vector<unsigned char> bytes = decode_base64(a.data, fail);
    if (a.encoding == "GZipBase64Binary") bytes = inflate_exactly(bytes, static_cast<size_t>(n) * size, where);
    if (bytes.size() != static_cast<size_t>(n) * size)
      throw InputError(where + std::to_string(bytes.size()) + " bytes of data; its dimensions give " +
                       std::to_string(static_cast<size_t>(n) * size));
    if (a.big_endian)
      for (size_t i = 0; i < bytes.size(); i += size) std::reverse(bytes.begin() + i, bytes.begin() + i + size);
    v = vtk_values(bytes, type, fail);
  }
  return a.column_major && a.dims.size() > 1 ? to_row_major(v, a.dims) : v;
}

}  // namespace vpm::detail
