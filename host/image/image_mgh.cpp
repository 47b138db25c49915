// FreeSurfer MGH volumes (.mgh raw, .mgz gzip-compressed; read through zlib's gz reader, which
// reads both). The format: a 284-byte big-endian header (version 1; width, height, depth,
// frames; data type; dof; goodRASflag; voxel sizes; direction cosines; centre RAS), then the
// voxels, big-endian, i fastest, then optional tags (ignored). The voxel -> RAS affine is the one
// FreeSurfer and nibabel compute: columns Mdc_j * delta_j, translation c_ras - M (dims / 2).
// The file is untrusted: every size is checked against what the header allows and against the
// bytes actually present before anything of that size is allocated.
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "vpm/memory.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"

namespace vpm {
namespace {

constexpr size_t kHeaderBytes = 284;
constexpr size_t kMaxVoxels = size_t(1) << 31;  // Image indexes voxels with int dims

std::uint32_t be32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | std::uint32_t(p[3]);
}
std::int32_t be_i32(const unsigned char* p) { return static_cast<std::int32_t>(be32(p)); }
std::int16_t be_i16(const unsigned char* p) { return static_cast<std::int16_t>((p[0] << 8) | p[1]); }
float be_f32(const unsigned char* p) {
  const std::uint32_t u = be32(p);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

struct GzCloser {
  void operator()(gzFile f) const { gzclose(f); }
};
using GzPtr = std::unique_ptr<std::remove_pointer_t<gzFile>, GzCloser>;

// Appends up to `want` bytes of the (decompressed) stream to `out`, growing it only by what was
// read; returns the bytes read. A corrupt gzip stream is an InputError.
size_t read_some(gzFile f, const std::string& path, size_t want, std::vector<unsigned char>& out) {
  size_t got = 0;
  while (got < want) {
    const unsigned chunk = static_cast<unsigned>(std::min<size_t>(want - got, size_t(1) << 24));
    const size_t at = out.size();
    out.resize(at + chunk);
    const int n = gzread(f, out.data() + at, chunk);
    if (n < 0) {
      int code = 0;
      const char* msg = gzerror(f, &code);
      throw InputError(path + ": not a readable MGH/MGZ file (" + std::string(msg ? msg : "read error") + ")");
    }
    out.resize(at + static_cast<size_t>(n));
    got += static_cast<size_t>(n);
    if (n == 0) break;
  }
  return got;
}

struct MghHeader {
  std::array<int, 4> dims{};
  int type = 0;
  short good_ras = 0;
  std::array<float, 3> delta{1, 1, 1};
  std::array<float, 9> mdc{};  // rows: the i, j, k axes' direction cosines (x_r x_a x_s, ...)
  std::array<float, 3> centre{};
};

MghHeader parse_header(const unsigned char* h, const std::string& path) {
  if (be_i32(h) != 1)
    throw InputError(path + ": not an MGH volume (version " + std::to_string(be_i32(h)) + " in the header, expected 1)");
  MghHeader m;
  for (int a = 0; a < 4; ++a) m.dims[a] = be_i32(h + 4 + 4 * a);
  m.type = be_i32(h + 20);
  m.good_ras = be_i16(h + 28);
  for (int a = 0; a < 3; ++a) m.delta[a] = be_f32(h + 30 + 4 * a);
  for (int a = 0; a < 9; ++a) m.mdc[a] = be_f32(h + 42 + 4 * a);
  for (int a = 0; a < 3; ++a) m.centre[a] = be_f32(h + 78 + 4 * a);
  for (int a = 0; a < 4; ++a)
    if (m.dims[a] < 1)
      throw InputError(path + ": MGH header: dimension " + std::to_string(a + 1) + " is " + std::to_string(m.dims[a]));
  if (m.dims[3] != 1)
    throw InputError(path + ": MGH volume has " + std::to_string(m.dims[3]) + " frames; vpm reads 3-D volumes (one frame)");
  if (m.good_ras <= 0) {  // FreeSurfer's (and nibabel's) default: coronal slices, 1 mm, centred
    m.delta = {1, 1, 1};
    m.mdc = {-1, 0, 0, 0, 0, -1, 0, 1, 0};
    m.centre = {0, 0, 0};
  }
  for (float v : m.delta)
    if (!(std::isfinite(v) && v > 0)) throw InputError(path + ": MGH header: voxel size " + std::to_string(v) + " is not positive");
  for (float v : m.mdc)
    if (!std::isfinite(v)) throw InputError(path + ": MGH header: direction cosines are not finite");
  return m;
}

size_t bytes_per_voxel(int type, const std::string& path) {
  switch (type) {
    case 0: return 1;  // MRI_UCHAR
    case 1: return 4;  // MRI_INT
    case 3: return 4;  // MRI_FLOAT
    case 4: return 2;  // MRI_SHORT
    default:
      throw InputError(path + ": MGH data type " + std::to_string(type) +
                       " is not one vpm reads (0 uchar, 1 int, 3 float, 4 short)");
  }
}

float voxel_value(const unsigned char* p, int type) {
  switch (type) {
    case 0: return static_cast<float>(*p);
    case 1: return static_cast<float>(be_i32(p));
    case 3: return be_f32(p);
    default: return static_cast<float>(be_i16(p));
  }
}

// A voxel-to-world matrix vpm can invert: finite (voxel sizes or a centre near the float range
// overflow), and axes that span space (|det| of the unit axes above 1e-6: no zero or parallel
// direction cosines).
void check_affine(const Eigen::Matrix4d& a, const std::string& path) {
  if (!a.allFinite()) throw InputError(path + ": MGH header: the voxel-to-world matrix is not finite (voxel sizes, centre)");
  Eigen::Matrix3d unit = a.topLeftCorner<3, 3>();
  for (int j = 0; j < 3; ++j) {
    const double n = unit.col(j).norm();
    if (!(n > 0)) throw InputError(path + ": MGH header: direction cosines of axis " + std::to_string(j + 1) + " are zero");
    unit.col(j) /= n;
  }
  if (!(std::abs(unit.determinant()) > 1e-6))
    throw InputError(path + ": MGH header: the direction cosines are parallel (the axes do not span space)");
}

Eigen::Matrix4d mgh_affine(const MghHeader& m) {
  Eigen::Matrix3d md;  // column j: axis j's direction cosines times its voxel size
  for (int j = 0; j < 3; ++j)
    for (int r = 0; r < 3; ++r) md(r, j) = double(m.mdc[3 * j + r]) * m.delta[j];
  const Eigen::Vector3d half(m.dims[0] / 2.0, m.dims[1] / 2.0, m.dims[2] / 2.0);
  Eigen::Matrix4d a = Eigen::Matrix4d::Identity();
  a.topLeftCorner<3, 3>() = md;
  a.topRightCorner<3, 1>() = Eigen::Vector3d(m.centre[0], m.centre[1], m.centre[2]) - md * half;
  return a;
}

}  // namespace

bool is_mgh_path(const std::string& path) {
  auto ends = [&](const char* s) {
    const size_t n = std::strlen(s);
    if (path.size() < n) return false;
    for (size_t i = 0; i < n; ++i)
      if (std::tolower(static_cast<unsigned char>(path[path.size() - n + i])) != s[i]) return false;
    return true;
  };
  return ends(".mgh") || ends(".mgz") || ends(".mgh.gz");
}

Image read_mgh(const std::string& path) {
  GzPtr f(gzopen(path.c_str(), "rb"));
  if (!f) throw InputError(path + ": cannot be opened");
  std::vector<unsigned char> buf;
  if (read_some(f.get(), path, kHeaderBytes, buf) < kHeaderBytes)
    throw InputError(path + ": truncated: " + std::to_string(buf.size()) + " bytes, shorter than the 284-byte MGH header");
  const MghHeader m = parse_header(buf.data(), path);
  const size_t bpv = bytes_per_voxel(m.type, path);
  size_t voxels = size_t(m.dims[0]) * size_t(m.dims[1]);  // each dimension < 2^31: no overflow in 64 bits
  if (voxels <= kMaxVoxels) voxels *= size_t(m.dims[2]);
  if (voxels > kMaxVoxels)
    throw InputError(path + ": MGH header: " + std::to_string(m.dims[0]) + " x " + std::to_string(m.dims[1]) + " x " +
                     std::to_string(m.dims[2]) + " voxels is more than vpm reads");
  // the raw voxels and the float image at once: refused up front when more than the memory
  require_memory(double(voxels) * double(bpv + sizeof(float)), path,
                 std::to_string(voxels) + " voxels x " + std::to_string(bpv + sizeof(float)) + " bytes");
  buf.clear();
  const size_t want = voxels * bpv;
  const size_t got = read_some(f.get(), path, want, buf);  // grows only with the bytes present
  if (got < want)
    throw InputError(path + ": truncated: the header says " + std::to_string(want) + " bytes of voxels, the file holds " +
                     std::to_string(got));
  Image img;
  img.dims = {m.dims[0], m.dims[1], m.dims[2]};
  img.affine = mgh_affine(m);
  check_affine(img.affine, path);
  for (int j = 0; j < 3; ++j) img.spacing[j] = img.affine.block<3, 1>(0, j).norm();
  img.affine_source = "mgh";
  img.path = path;
  img.data.resize(voxels);
  for (size_t v = 0; v < voxels; ++v) img.data[v] = voxel_value(buf.data() + v * bpv, m.type);
  return img;
}

Image read_image(const std::string& path) { return is_mgh_path(path) ? read_mgh(path) : read_nifti(path); }

}  // namespace vpm
