// FreeSurfer triangle surfaces (lh.white, lh.pial, lh.sphere, ...), the binary format FreeSurfer's
// mris_write writes: the 3-byte magic FF FF FE, a "created by" text line ended by two newlines,
// big-endian int32 vertex and face counts, the vertices as big-endian float32 x y z, the faces as
// big-endian int32 index triples; anything after them (FreeSurfer's volume geometry tags) is
// ignored. Quadrangle surfaces (magic FF FF FF or FF FF FD) are refused with the conversion to
// use. Per-vertex files (.curv, .thickness, .sulc: magic FF FF FF, big-endian int32 vertex,
// face and values-a-vertex counts, float32 values) are read as overlays. Errors give the byte
// offset ("PATH:byte N: ...").
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

[[noreturn]] void fail_byte(const std::string& path, size_t offset, const std::string& what) {
  throw InputError(path + ":byte " + std::to_string(offset) + ": " + what);
}

uint32_t be32(const std::string& d, size_t at) {
  const auto* p = reinterpret_cast<const unsigned char*>(d.data() + at);
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}

void put_be32(std::string& out, uint32_t v) {
  const char b[4] = {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
                     static_cast<char>(v)};
  out.append(b, 4);
}

// Limits that keep a corrupt header from sizing an allocation: the counts must fit the file.
constexpr long long kMaxCount = 1LL << 30;

}  // namespace

bool is_freesurfer_surface(const std::string& head) {
  return head.size() >= 3 && static_cast<unsigned char>(head[0]) == 0xFF &&
         static_cast<unsigned char>(head[1]) == 0xFF &&
         (static_cast<unsigned char>(head[2]) == 0xFE || static_cast<unsigned char>(head[2]) == 0xFF ||
          static_cast<unsigned char>(head[2]) == 0xFD);
}

TriSurface read_freesurfer(const std::string& path) {
  const std::string d = read_whole_file(path);
  if (d.size() < 3 || !is_freesurfer_surface(d))
    fail_byte(path, 0, "not a FreeSurfer surface (its first bytes are not FF FF FE)");
  if (static_cast<unsigned char>(d[2]) != 0xFE)
    fail_byte(path, 0, "a FreeSurfer quadrangle surface; convert it to triangles first (mris_convert IN OUT.gii, or "
                       "FreeSurfer's mris_convert to a triangle surface)");
  // the "created by" line ends at the first "\n\n" (nibabel and mris_write agree)
  const size_t end = d.find("\n\n", 3);
  if (end == std::string::npos || end > 3 + 4096)
    fail_byte(path, 3, "no end of the 'created by' line (two newlines) within 4 KB: not a FreeSurfer surface or truncated");
  size_t at = end + 2;
  if (d.size() < at + 8) fail_byte(path, at, "truncated before the vertex and face counts");
  const long long nv = static_cast<int32_t>(be32(d, at)), nf = static_cast<int32_t>(be32(d, at + 4));
  if (nv < 3 || nv > kMaxCount) fail_byte(path, at, "vertex count " + std::to_string(nv) + " out of range");
  if (nf < 1 || nf > kMaxCount) fail_byte(path, at + 4, "face count " + std::to_string(nf) + " out of range");
  at += 8;
  const unsigned long long need = at + 12ULL * static_cast<unsigned long long>(nv) + 12ULL * static_cast<unsigned long long>(nf);
  if (d.size() < need)
    fail_byte(path, d.size(), "truncated: " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                                  " faces need " + std::to_string(need) + " bytes, the file has " + std::to_string(d.size()));
  TriSurface s;
  s.vertices.resize(nv, 3);
  for (long long i = 0; i < nv; ++i)
    for (int k = 0; k < 3; ++k) {
      const size_t off = at + 12 * static_cast<size_t>(i) + 4 * static_cast<size_t>(k);
      const float f = std::bit_cast<float>(be32(d, off));
      if (!std::isfinite(f)) fail_byte(path, off, "vertex " + std::to_string(i) + ": coordinate is not a finite number");
      s.vertices(i, k) = f;
    }
  at += 12 * static_cast<size_t>(nv);
  s.triangles.resize(nf, 3);
  for (long long t = 0; t < nf; ++t)
    for (int k = 0; k < 3; ++k) {
      const size_t off = at + 12 * static_cast<size_t>(t) + 4 * static_cast<size_t>(k);
      const long long v = static_cast<int32_t>(be32(d, off));
      if (v < 0 || v >= nv)
        fail_byte(path, off, "face " + std::to_string(t) + ": vertex index " + std::to_string(v) + " out of range (" +
                                 std::to_string(nv) + " vertices)");
      s.triangles(t, k) = static_cast<int>(v);
    }
  return s;
}

Eigen::VectorXd read_freesurfer_curv(const std::string& path) {
  const std::string d = read_whole_file(path);
  if (d.size() < 15 || static_cast<unsigned char>(d[0]) != 0xFF || static_cast<unsigned char>(d[1]) != 0xFF ||
      static_cast<unsigned char>(d[2]) != 0xFF)
    fail_byte(path, 0, "not a FreeSurfer per-vertex file (.curv, .thickness, .sulc, ...: its first bytes are not FF FF FF)");
  const long long nv = static_cast<int32_t>(be32(d, 3)), per = static_cast<int32_t>(be32(d, 11));
  if (nv < 1 || nv > kMaxCount) fail_byte(path, 3, "vertex count " + std::to_string(nv) + " out of range");
  if (per != 1) fail_byte(path, 11, std::to_string(per) + " values a vertex; vpm reads files of one");
  if (d.size() < 15 + 4ULL * static_cast<unsigned long long>(nv))
    fail_byte(path, d.size(), "truncated: " + std::to_string(nv) + " values need " + std::to_string(15 + 4 * nv) +
                                  " bytes, the file has " + std::to_string(d.size()));
  Eigen::VectorXd v(nv);
  for (long long i = 0; i < nv; ++i) {
    const size_t off = 15 + 4 * static_cast<size_t>(i);
    const float x = std::bit_cast<float>(be32(d, off));
    if (!std::isfinite(x)) fail_byte(path, off, "vertex " + std::to_string(i) + ": value is not a finite number");
    v(i) = x;
  }
  return v;
}

void write_freesurfer(const std::string& path, const TriSurface& s) {
  std::string out;
  out.reserve(64 + 12 * static_cast<size_t>(s.vertices.rows() + s.triangles.rows()));
  out.append("\xFF\xFF\xFE", 3);
  out.append("created by vpm\n\n");
  put_be32(out, static_cast<uint32_t>(s.vertices.rows()));
  put_be32(out, static_cast<uint32_t>(s.triangles.rows()));
  for (Eigen::Index i = 0; i < s.vertices.rows(); ++i)
    for (int k = 0; k < 3; ++k) put_be32(out, std::bit_cast<uint32_t>(static_cast<float>(s.vertices(i, k))));
  for (Eigen::Index i = 0; i < s.triangles.rows(); ++i)
    for (int k = 0; k < 3; ++k) put_be32(out, static_cast<uint32_t>(s.triangles(i, k)));
  AtomicFile file(path, true);
  file.stream().write(out.data(), static_cast<std::streamsize>(out.size()));
  file.commit();
}

}  // namespace vpm::detail
