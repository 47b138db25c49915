// Header checks before nifti_clib allocates from a NIfTI header (with_nifti/nifti_header.hpp).
#include "with_nifti/nifti_header.hpp"

#include <nifti2_io.h>
#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>

#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/memory.hpp"

namespace vpm::detail {

namespace {

// The fields checked here, from either header version (already in host byte order).
struct Fields {
  int version = 1;
  bool one_file = true;
  std::int64_t dim[8] = {};
  double pixdim[8] = {};
  int datatype = 0;
  double vox_offset = 0, scl_slope = 0, scl_inter = 0;
  int qform_code = 0, sform_code = 0;
  double quatern[6] = {};  // b, c, d, qoffset x, y, z
  double srow[12] = {};
};

template <class H>
Fields fields_of(const H& h, int version) {
  Fields f;
  f.version = version;
  f.one_file = h.magic[1] == '+';
  for (int i = 0; i < 8; ++i) f.dim[i] = h.dim[i], f.pixdim[i] = h.pixdim[i];
  f.datatype = h.datatype;
  f.vox_offset = double(h.vox_offset);
  f.scl_slope = h.scl_slope, f.scl_inter = h.scl_inter;
  f.qform_code = h.qform_code, f.sform_code = h.sform_code;
  const double q[6] = {double(h.quatern_b), double(h.quatern_c), double(h.quatern_d),
                       double(h.qoffset_x), double(h.qoffset_y), double(h.qoffset_z)};
  for (int i = 0; i < 6; ++i) f.quatern[i] = q[i];
  for (int i = 0; i < 4; ++i) f.srow[i] = h.srow_x[i], f.srow[4 + i] = h.srow_y[i], f.srow[8 + i] = h.srow_z[i];
  return f;
}

// The first bytes of the file (decompressed when gzip): nifti_clib's own header readers are
// only given a header whose size field and magic agree (libnifti2 2.0.0's nifti_read_n1_hdr
// smashes its stack on a 348-byte header carrying the NIfTI-2 magic, found by fuzz_nifti).
void check_size_and_magic(const std::string& path) {
  unsigned char b[540] = {};
  int got = 0;
  if (gzFile g = gzopen(path.c_str(), "rb")) {
    got = gzread(g, b, sizeof b);
    gzclose(g);
  }
  if (got < 348) throw InputError(path + ": header: cannot read the 348-byte NIfTI-1 header (file too short?)");
  std::uint32_t le = 0;
  std::memcpy(&le, b, 4);
  const std::uint32_t be = __builtin_bswap32(le);
  const auto is = [&](const unsigned char* at, const char* magic, size_t n) { return std::memcmp(at, magic, n) == 0; };
  if (le == 348 || be == 348) {
    static const unsigned char none[4] = {0, 0, 0, 0};  // ANALYZE 7.5, which nifti_clib reads too
    if (is(b + 344, "n+1", 4) || is(b + 344, "ni1", 4) || std::memcmp(b + 344, none, 4) == 0) return;
    throw InputError(path + ": header: sizeof_hdr is 348 (NIfTI-1) but the magic at byte 344 is not \"n+1\" or \"ni1\"");
  }
  if (le == 540 || be == 540) {
    if (got < 540) throw InputError(path + ": header: cannot read the 540-byte NIfTI-2 header (file too short?)");
    if (is(b + 4, "n+2\0\r\n\032\n", 8) || is(b + 4, "ni2\0\r\n\032\n", 8)) return;
    throw InputError(path + ": header: sizeof_hdr is 540 (NIfTI-2) but the magic at byte 4 is not \"n+2\" or \"ni2\"");
  }
  throw InputError(path + ": header: sizeof_hdr is " + std::to_string(le) + ", neither 348 (NIfTI-1) nor 540 (NIfTI-2)");
}

// The header in host byte order (nifti_clib swaps it), version from the sizeof_hdr/magic.
Fields read_fields(const std::string& path) {
  check_size_and_magic(path);
  int version = 0;
  std::free(nifti_read_header(path.c_str(), &version, 0));
  if (version == 2) {
    std::unique_ptr<nifti_2_header, decltype(&std::free)> h(nifti_read_n2_hdr(path.c_str(), nullptr, 0), &std::free);
    if (!h) throw InputError(path + ": header: cannot read the 540-byte NIfTI-2 header (file too short?)");
    return fields_of(*h, 2);
  }
  std::unique_ptr<nifti_1_header, decltype(&std::free)> h(nifti_read_n1_hdr(path.c_str(), nullptr, 0), &std::free);
  if (!h) throw InputError(path + ": header: cannot read the 348-byte NIfTI-1 header (file too short?)");
  return fields_of(*h, 1);
}

bool gzip_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char b[2] = {0, 0};
  in.read(reinterpret_cast<char*>(b), 2);
  return in && b[0] == 0x1f && b[1] == 0x8b;
}

void bad(const std::string& path, const std::string& what) { throw InputError(path + ": header: " + what); }

std::string num(double v) { return format_sig(v, 6); }

NiftiHeaderSizes check_dims(const std::string& path, const Fields& f) {
  if (f.dim[0] < 1 || f.dim[0] > 7) bad(path, "invalid dimensions (dim[0] = " + std::to_string(f.dim[0]) + ", expected 1 to 7)");
  for (int d = 1; d <= f.dim[0]; ++d)
    if (f.dim[d] < 1) bad(path, "dim[" + std::to_string(d) + "] = " + std::to_string(f.dim[d]) + " (must be at least 1)");
  for (int d = 4; d <= f.dim[0]; ++d)
    if (f.dim[d] > 1)
      bad(path, "a " + std::to_string(f.dim[0]) + "-D image (dim[" + std::to_string(d) + "] = " + std::to_string(f.dim[d]) +
                    "); mesh-image needs one 3-D volume: extract it first");
  NiftiHeaderSizes s;
  s.nx = f.dim[1];
  s.ny = f.dim[0] >= 2 ? f.dim[2] : 1;
  s.nz = f.dim[0] >= 3 ? f.dim[3] : 1;
  if (s.nx > 100000 || s.ny > 100000 || s.nz > 100000 || s.nx * s.ny * s.nz > (std::int64_t(1) << 31))
    bad(path, "image too large (" + std::to_string(s.nx) + "x" + std::to_string(s.ny) + "x" + std::to_string(s.nz) +
                  "; at most 100000 a side and 2^31 voxels)");
  int swapsize = 0;
  switch (f.datatype) {
    case DT_UINT8: case DT_INT8: case DT_INT16: case DT_UINT16: case DT_INT32: case DT_UINT32:
    case DT_INT64: case DT_UINT64: case DT_FLOAT32: case DT_FLOAT64: break;
    default:
      bad(path, "unsupported data type " + std::to_string(f.datatype) + " (" + nifti_datatype_string(f.datatype) +
                    "); need a real scalar type");
  }
  nifti_datatype_sizes(f.datatype, &s.bytes_per_voxel, &swapsize);
  s.data_bytes = s.nx * s.ny * s.nz * s.bytes_per_voxel;
  return s;
}

// Voxel sizes, scale factors and the two affines: finite where used (nifti_clib would replace
// bad values silently).
void check_geometry(const std::string& path, const Fields& f) {
  for (int d = 1; d <= 3; ++d) {
    const double p = f.pixdim[d];
    if (!std::isfinite(p)) bad(path, "pixdim[" + std::to_string(d) + "] = " + num(p) + " (voxel size not finite)");
    if (f.sform_code <= 0 && d <= f.dim[0] && !(p > 0))
      bad(path, "pixdim[" + std::to_string(d) + "] = " + num(p) +
                    " (the voxel size must be positive when no sform gives the affine)");
  }
  // NaN scl_slope means "no scaling" (nibabel writes it); infinities are not scale factors
  if (std::isinf(f.scl_slope)) bad(path, "scl_slope = " + num(f.scl_slope) + " (not a finite scale factor)");
  if (std::isfinite(f.scl_slope) && f.scl_slope != 0 && !std::isfinite(f.scl_inter))
    bad(path, "scl_inter = " + num(f.scl_inter) + " with scl_slope = " + num(f.scl_slope) + " (not a finite offset)");
  if (f.sform_code > 0)
    for (int i = 0; i < 12; ++i)
      if (!std::isfinite(f.srow[i]))
        bad(path, std::string("srow_") + "xyz"[i / 4] + "[" + std::to_string(i % 4) + "] = " + num(f.srow[i]) +
                      " (sform not finite)");
  if (f.qform_code > 0)
    for (int i = 0; i < 6; ++i)
      if (!std::isfinite(f.quatern[i]))
        bad(path, std::string(i < 3 ? "quatern_" : "qoffset_") + "bcdxyz"[i] + " = " + num(f.quatern[i]) +
                      " (qform not finite)");
}

// The declared data must fit in the file that holds it (a plain file exactly; a gzip file
// within deflate's largest expansion, about 1032:1).
void check_file_size(const std::string& path, const Fields& f, const NiftiHeaderSizes& s) {
  const double header = f.version == 2 ? 540 : 348;
  if (!std::isfinite(f.vox_offset) || f.vox_offset < 0 || f.vox_offset > 1e15 || (f.one_file && f.vox_offset < header))
    bad(path, "vox_offset = " + num(f.vox_offset) + " (must be finite and at least the header's " + num(header) +
                  " bytes)");
  std::string data_path = path;
  if (!f.one_file) {
    std::unique_ptr<char, decltype(&std::free)> img(
        nifti_findimgname(path.c_str(), f.version == 2 ? NIFTI_FTYPE_NIFTI2_2 : NIFTI_FTYPE_NIFTI1_2), &std::free);
    if (!img) throw InputError(path + ": no image file (.img) next to this two-file NIfTI header");
    data_path = img.get();
  }
  std::error_code ec;
  const auto size = std::filesystem::file_size(data_path, ec);
  if (ec) throw InputError(data_path + ": cannot read its size: " + ec.message());
  const double need = std::floor(f.vox_offset) + double(s.data_bytes);
  const bool gz = gzip_file(data_path);
  if (!gz && f.vox_offset > double(size))
    bad(path, "vox_offset = " + num(f.vox_offset) + " lies past the end of the file (" + std::to_string(size) + " bytes)");
  if (gz) {
    if (need > 1032.0 * double(size) + 4096)
      throw InputError(data_path + ": data: the header declares " + format_bytes(need) + " (" + std::to_string(s.nx) +
                       "x" + std::to_string(s.ny) + "x" + std::to_string(s.nz) + " voxels), more than this " +
                       format_bytes(double(size)) + " gzip file can hold (deflate expands at most 1032x)");
  } else if (double(size) < need) {
    throw InputError(data_path + ": data: truncated: the header declares " + std::to_string(std::int64_t(need)) +
                     " bytes, the file has " +
                     std::to_string(size));
  }
}

}  // namespace

NiftiHeaderSizes check_nifti_header(const std::string& path) {
  const Fields f = read_fields(path);
  const NiftiHeaderSizes s = check_dims(path, f);
  check_geometry(path, f);
  check_file_size(path, f, s);
  // the stored voxels and their float copy (Image::data) are alive together while reading
  const double voxels = double(s.nx) * double(s.ny) * double(s.nz);
  require_memory(voxels * (s.bytes_per_voxel + 4.0), path,
                 std::to_string(s.nx) + "x" + std::to_string(s.ny) + "x" + std::to_string(s.nz) + " voxels x (" +
                     std::to_string(s.bytes_per_voxel) + " stored + 4) bytes");
  return s;
}

}  // namespace vpm::detail
