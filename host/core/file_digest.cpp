// The digest line of vpm's binary files (core/file_digest.hpp). (Not instrumented for the
// fuzzers, like the rest of core/: the comparison of a digest gives them nothing to learn.)
#include "core/file_digest.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <vector>

#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

const std::string kMagic = "vpm hdf5 crc32 ";

std::uint32_t update(std::uint32_t crc, const char* data, std::size_t size) {
  uLong c = crc;
  for (std::size_t done = 0; done < size;) {
    const std::size_t n = std::min<std::size_t>(size - done, std::size_t{1} << 30);
    c = crc32(c, reinterpret_cast<const Bytef*>(data + done), static_cast<uInt>(n));
    done += n;
  }
  return static_cast<std::uint32_t>(c);
}

}  // namespace

std::string digest_line(const char* data, std::size_t size) {
  char hex[9];
  std::snprintf(hex, sizeof hex, "%08x", update(static_cast<std::uint32_t>(crc32(0L, Z_NULL, 0)), data, size));
  return kMagic + hex + "\n";
}

void check_digest(const std::string& path, std::size_t header, const std::string& missing) {
  std::ifstream in(path, std::ios::binary);
  std::string head(header, '\0');
  if (!in.read(head.data(), static_cast<std::streamsize>(head.size())) || head.compare(0, kMagic.size(), kMagic) != 0)
    throw InputError(path + ": " + missing);
  std::uint32_t stored = 0;
  for (std::size_t i = kMagic.size(); i < kMagic.size() + 8; ++i) {
    const char c = head[i];
    const int v = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
    if (v < 0) throw InputError(path + ": the digest at its start is malformed");
    stored = stored << 4 | static_cast<std::uint32_t>(v);
  }
  std::uint32_t crc = static_cast<std::uint32_t>(crc32(0L, Z_NULL, 0));
  std::vector<char> block(std::size_t{1} << 20);
  while (in.read(block.data(), static_cast<std::streamsize>(block.size())) || in.gcount() > 0)
    crc = update(crc, block.data(), static_cast<std::size_t>(in.gcount()));
  if (stored != crc) throw InputError(path + ": its contents do not match their digest (a truncated or corrupt file)");
}

}  // namespace vpm::detail
