#include "io/vtk_binary.hpp"

#include <zlib.h>

#include <cstdint>
#include <cstring>

namespace vpm::detail {

namespace {

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

bool is_space(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

// Little-endian unsigned integer of `bytes` bytes at p.
std::uint64_t read_uint(const unsigned char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

// The characters of `text` that are not whitespace.
std::string compact(std::string_view text) {
  std::string s;
  s.reserve(text.size());
  for (char c : text)
    if (!is_space(c)) s.push_back(c);
  return s;
}

// Base64 characters holding `bytes` bytes encoded on their own (with padding).
size_t encoded_length(size_t bytes) { return (bytes + 2) / 3 * 4; }

// zlib blocks after a compression header at h (header_bytes each: blocks, block size, last
// size, compressed sizes); `data` the compressed bytes that follow.
std::vector<unsigned char> inflate_blocks(const unsigned char* h, const unsigned char* data, size_t data_avail,
                                          const VtkBinaryLayout& L, size_t& used, const VtkBinaryFail& fail) {
  const std::uint64_t blocks = read_uint(h, L.header_bytes), size = read_uint(h + L.header_bytes, L.header_bytes),
                      last = read_uint(h + 2 * L.header_bytes, L.header_bytes);
  std::vector<unsigned char> out;
  size_t at = 0;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint64_t csize = read_uint(h + (3 + b) * L.header_bytes, L.header_bytes);
    const std::uint64_t usize = b + 1 == blocks && last != 0 ? last : size;
    if (csize > data_avail - at) fail("compressed block " + std::to_string(b) + " runs past the data (truncated file?)");
    // zlib cannot expand by more than about 1032x: a larger claim is a corrupt header, not memory to reserve
    if (usize > 1100 * csize + 64) fail("compressed block " + std::to_string(b) + " claims " + std::to_string(usize) +
                                        " bytes from " + std::to_string(csize));
    const size_t start = out.size();
    out.resize(start + usize);
    uLongf len = static_cast<uLongf>(usize);
    if (uncompress(out.data() + start, &len, data + at, static_cast<uLong>(csize)) != Z_OK || len != usize)
      fail("compressed block " + std::to_string(b) + " does not inflate to " + std::to_string(usize) + " bytes");
    at += csize;
  }
  used = at;
  return out;
}

}  // namespace

std::string encode_base64(std::string_view in) {
  static const char* A = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  for (size_t i = 0; i < in.size(); i += 3) {
    const unsigned n = (static_cast<unsigned char>(in[i]) << 16) |
                       (i + 1 < in.size() ? static_cast<unsigned char>(in[i + 1]) << 8 : 0) |
                       (i + 2 < in.size() ? static_cast<unsigned char>(in[i + 2]) : 0);
    out += A[(n >> 18) & 63];
    out += A[(n >> 12) & 63];
    out += i + 1 < in.size() ? A[(n >> 6) & 63] : '=';
    out += i + 2 < in.size() ? A[n & 63] : '=';
  }
  return out;
}

std::vector<unsigned char> decode_base64(std::string_view text, const VtkBinaryFail& fail) {
  std::vector<unsigned char> out;
  out.reserve(text.size() / 4 * 3);
  unsigned buf = 0;
  int bits = 0;
  size_t chars = 0, pad = 0;
  for (char c : text) {
    if (is_space(c)) continue;
    ++chars;
    if (c == '=') {
      ++pad;
      continue;
    }
    const int v = base64_value(c);
    if (v < 0 || pad) fail(std::string("'") + c + "' in base64 data");
    buf = (buf << 6) | static_cast<unsigned>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<unsigned char>((buf >> bits) & 0xff));
    }
  }
  if (chars % 4 != 0 || pad > 2) fail("base64 data of " + std::to_string(chars) + " characters (truncated?)");
  return out;
}

std::vector<unsigned char> vtk_raw_blob(const unsigned char* p, size_t avail, const VtkBinaryLayout& L, size_t& used,
                                        const VtkBinaryFail& fail) {
  if (L.big_endian) fail("big-endian binary data are not supported (byte_order=\"BigEndian\")");
  const size_t hb = static_cast<size_t>(L.header_bytes);
  if (avail < hb * (L.zlib ? 3 : 1)) fail("binary data end inside a header (truncated file?)");
  if (!L.zlib) {
    const std::uint64_t n = read_uint(p, L.header_bytes);
    if (n > avail - hb) fail("binary array of " + std::to_string(n) + " bytes runs past the data (truncated file?)");
    used = hb + n;
    return std::vector<unsigned char>(p + hb, p + hb + n);
  }
  const std::uint64_t blocks = read_uint(p, L.header_bytes);
  if (blocks > (avail - 3 * hb) / hb) fail("compression header of " + std::to_string(blocks) + " blocks runs past the data");
  const size_t header = (3 + blocks) * hb;
  size_t data = 0;
  std::vector<unsigned char> out = inflate_blocks(p, p + header, avail - header, L, data, fail);
  used = header + data;
  return out;
}

std::vector<unsigned char> vtk_base64_blob(std::string_view text, const VtkBinaryLayout& L, const VtkBinaryFail& fail) {
  if (L.big_endian) fail("big-endian binary data are not supported (byte_order=\"BigEndian\")");
  const std::string s = compact(text);
  const size_t hb = static_cast<size_t>(L.header_bytes);
  if (!L.zlib) {
    // the header and the data encoded together, or apart (the header's padding shows then)
    const size_t h = encoded_length(hb);
    if (s.size() < h) fail("base64 data end inside a header (truncated file?)");
    if (s.size() == h || s[h - 1] != '=') {
      const std::vector<unsigned char> all = decode_base64(s, fail);
      if (read_uint(all.data(), L.header_bytes) != all.size() - hb)
        fail("binary array header says " + std::to_string(read_uint(all.data(), L.header_bytes)) + " bytes, the data hold " +
             std::to_string(all.size() - hb));
      return std::vector<unsigned char>(all.begin() + static_cast<long>(hb), all.end());
    }
    const std::vector<unsigned char> head = decode_base64(std::string_view(s).substr(0, h), fail);
    std::vector<unsigned char> data = decode_base64(std::string_view(s).substr(h), fail);
    if (read_uint(head.data(), L.header_bytes) != data.size())
      fail("binary array header says " + std::to_string(read_uint(head.data(), L.header_bytes)) + " bytes, the data hold " +
           std::to_string(data.size()));
    return data;
  }
  // compressed: [blocks, size, last] first (3 * hb bytes: 4 * hb characters), then the block sizes
  if (s.size() < 4 * hb) fail("base64 data end inside a compression header (truncated file?)");
  const std::vector<unsigned char> first = decode_base64(std::string_view(s).substr(0, 4 * hb), fail);
  const std::uint64_t blocks = read_uint(first.data(), L.header_bytes);
  if (blocks > s.size()) fail("compression header of " + std::to_string(blocks) + " blocks runs past the data");
  const size_t h = encoded_length((3 + blocks) * hb);
  if (s.size() < h) fail("base64 data end inside a compression header (truncated file?)");
  const std::vector<unsigned char> head = decode_base64(std::string_view(s).substr(0, h), fail);
  const std::vector<unsigned char> data = decode_base64(std::string_view(s).substr(h), fail);
  size_t used = 0;
  return inflate_blocks(head.data(), data.data(), data.size(), L, used, fail);
}

int vtk_type_size(const std::string& t) {
  if (t == "Int8" || t == "UInt8") return 1;
  if (t == "Int16" || t == "UInt16") return 2;
  if (t == "Int32" || t == "UInt32" || t == "Float32") return 4;
  if (t == "Int64" || t == "UInt64" || t == "Float64") return 8;
  return 0;
}

namespace {

// The n values of type T at p (little-endian, unaligned) as doubles.
template <class T>
void convert(const unsigned char* p, size_t n, std::vector<double>& v) {
  for (size_t i = 0; i < n; ++i, p += sizeof(T)) {
    T x;
    std::memcpy(&x, p, sizeof(T));
    v[i] = static_cast<double>(x);
  }
}

}  // namespace

std::vector<double> vtk_values(const std::vector<unsigned char>& bytes, const std::string& t, const VtkBinaryFail& fail) {
  const int size = vtk_type_size(t);
  if (size == 0) fail("binary data of type '" + t + "' (expected Int8..Int64, UInt8..UInt64, Float32, Float64)");
  if (bytes.size() % static_cast<size_t>(size)) fail(std::to_string(bytes.size()) + " bytes are not whole " + t + " values");
  const size_t n = bytes.size() / static_cast<size_t>(size);
  std::vector<double> v(n);
  const unsigned char* p = bytes.data();
  if (t == "Float64") convert<double>(p, n, v);  // the type is dispatched once, not per value
  else if (t == "Float32") convert<float>(p, n, v);
  else if (t == "Int8") convert<std::int8_t>(p, n, v);
  else if (t == "UInt8") convert<std::uint8_t>(p, n, v);
  else if (t == "Int16") convert<std::int16_t>(p, n, v);
  else if (t == "UInt16") convert<std::uint16_t>(p, n, v);
  else if (t == "Int32") convert<std::int32_t>(p, n, v);
  else if (t == "UInt32") convert<std::uint32_t>(p, n, v);
  else if (t == "Int64") convert<std::int64_t>(p, n, v);
  else convert<std::uint64_t>(p, n, v);
  return v;
}

}  // namespace vpm::detail
