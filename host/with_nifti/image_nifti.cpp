// NIfTI-1/2 reading and writing with nifti_clib (Debian libnifti2-dev).
#include <nifti2_io.h>
#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <algorithm>
#include <vector>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "core/atomic_file.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "with_nifti/nifti_header.hpp"

namespace vpm {

namespace {

struct NimDeleter {
  void operator()(nifti_image* n) const { nifti_image_free(n); }
};
using NimPtr = std::unique_ptr<nifti_image, NimDeleter>;

Eigen::Matrix4d to_eigen(const nifti_dmat44& m) {
  Eigen::Matrix4d a;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) a(r, c) = m.m[r][c];
  return a;
}

template <class T>
void convert(const void* src, size_t n, std::vector<float>& out) {
  const T* p = static_cast<const T*>(src);
  for (size_t i = 0; i < n; ++i) out[i] = static_cast<float>(p[i]);
}

bool gzip_magic(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char b[2] = {0, 0};
  in.read(reinterpret_cast<char*>(b), 2);
  return in && b[0] == 0x1f && b[1] == 0x8b;
}

}  // namespace

namespace {

// Loads the voxels after comparing the declared data size with the file (uncompressed files).
void load_voxels(const std::string& path, nifti_image* nim) {
  std::error_code ec;
  if (!gzip_magic(path) && nim->nifti_type != NIFTI_FTYPE_NIFTI1_2 && nim->nifti_type != NIFTI_FTYPE_NIFTI2_2) {
    const auto size = std::filesystem::file_size(path, ec);
    const int64_t need = int64_t(nim->iname_offset) + int64_t(nim->nvox) * nim->nbyper;
    if (!ec && int64_t(size) < need)
      throw InputError(path + ": data: truncated: the header declares " + std::to_string(need) +
                       " bytes, the file has " + std::to_string(size));
  }
  if (nifti_image_load(nim) < 0 || !nim->data)
    throw InputError(path + ": data: cannot read " + std::to_string(int64_t(nim->nvox) * nim->nbyper) +
                     " bytes of voxel data (truncated file or broken gzip stream)");
}

// The voxel values as floats, scaled by scl_slope / scl_inter when the file sets them.
std::vector<float> voxel_values(const nifti_image& nim, size_t n) {
  std::vector<float> data(n);
  switch (nim.datatype) {
    case DT_UINT8: convert<uint8_t>(nim.data, n, data); break;
    case DT_INT8: convert<int8_t>(nim.data, n, data); break;
    case DT_INT16: convert<int16_t>(nim.data, n, data); break;
    case DT_UINT16: convert<uint16_t>(nim.data, n, data); break;
    case DT_INT32: convert<int32_t>(nim.data, n, data); break;
    case DT_UINT32: convert<uint32_t>(nim.data, n, data); break;
    case DT_INT64: convert<int64_t>(nim.data, n, data); break;
    case DT_UINT64: convert<uint64_t>(nim.data, n, data); break;
    case DT_FLOAT32: convert<float>(nim.data, n, data); break;
    case DT_FLOAT64: convert<double>(nim.data, n, data); break;
  }
  const double slope = nim.scl_slope, inter = nim.scl_inter;
  if (std::isfinite(slope) && slope != 0 && !(slope == 1 && inter == 0))
    for (auto& v : data) v = float(slope * v + inter);
  return data;
}

// The voxel-to-world affine: sform, else qform, else the pixdim scaling; spacing checked.
void set_affine(const std::string& path, const nifti_image& nim, Image& img) {
  if (nim.sform_code > 0) {
    img.affine = to_eigen(nim.sto_xyz);
    img.affine_source = "sform";
  } else if (nim.qform_code > 0) {
    img.affine = to_eigen(nim.qto_xyz);
    img.affine_source = "qform";
  } else {
    img.affine = Eigen::Matrix4d::Identity();
    for (int d = 0; d < 3; ++d) img.affine(d, d) = nim.pixdim[d + 1] > 0 ? nim.pixdim[d + 1] : 1.0;
    img.affine_source = "pixdim";
  }
  img.affine.row(3) << 0, 0, 0, 1;
  for (int d = 0; d < 3; ++d) {
    img.spacing[d] = img.affine.col(d).head<3>().norm();
    if (!(img.spacing[d] > 0) || !std::isfinite(img.spacing[d]))
      throw InputError(path + ": header: degenerate " + img.affine_source + " (axis " + std::to_string(d) +
                       " has zero length)");
  }
  if (std::abs(img.affine.topLeftCorner<3, 3>().determinant()) < 1e-12)
    throw InputError(path + ": header: singular " + img.affine_source + " matrix");
}

}  // namespace

Image read_nifti(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path + ": no such file");
  if (fs::is_directory(path, ec)) throw InputError(path + ": is a directory, not a NIfTI file");
  nifti_set_debug_level(0);
  const int kind = is_nifti_file(path.c_str());
  if (kind <= 0)  // -1: error reading, 0: ANALYZE (no magic) or garbage
    throw InputError(path + ": header: not a NIfTI-1/2 file (no 'n+1'/'ni1'/'n+2' magic" +
                     std::string(gzip_magic(path) ? " in the decompressed stream" : "") +
                     "; file too short or not an image)");
  // the header is checked before nifti_clib allocates anything from it (sizes, NaNs, file size)
  const detail::NiftiHeaderSizes sizes = detail::check_nifti_header(path);
  NimPtr nim(nifti_image_read(path.c_str(), 0));
  if (!nim) throw InputError(path + ": header: nifti_clib cannot read the NIfTI header");
  const int64_t nx = sizes.nx, ny = sizes.ny, nz = sizes.nz;
  if (int64_t(nim->nvox) != nx * ny * nz || nim->nbyper != sizes.bytes_per_voxel)
    throw InputError(path + ": header: nifti_clib reads " + std::to_string(int64_t(nim->nvox)) + " voxels of " +
                     std::to_string(nim->nbyper) + " bytes, the header check " + std::to_string(nx * ny * nz) + " of " +
                     std::to_string(sizes.bytes_per_voxel));
  load_voxels(path, nim.get());
  Image img;
  img.path = path;
  img.dims = {int(nx), int(ny), int(nz)};
  img.data = voxel_values(*nim, size_t(nx * ny * nz));
  set_affine(path, *nim, img);
  return img;
}

namespace {

// Appends `n` bytes to `out`, gzip-compressed through `zs` when it is given (flush: the last piece).
void put(std::ostream& out, z_stream* zs, const void* data, size_t n, bool flush, const std::string& path) {
  if (!zs) {
    out.write(static_cast<const char*>(data), std::streamsize(n));
    return;
  }
  unsigned char buf[1 << 16];
  zs->next_in = static_cast<Bytef*>(const_cast<void*>(data));
  zs->avail_in = static_cast<uInt>(n);
  int rc = Z_OK;
  do {
    zs->next_out = buf;
    zs->avail_out = sizeof buf;
    rc = deflate(zs, flush ? Z_FINISH : Z_NO_FLUSH);
    if (rc == Z_STREAM_ERROR) throw InputError(path + ": gzip compression failed");
    out.write(reinterpret_cast<const char*>(buf), std::streamsize(sizeof buf - zs->avail_out));
  } while (zs->avail_out == 0 || (flush && rc != Z_STREAM_END));
}

// The NIfTI-1 header (nifti_clib fills it from the image), a 4-byte empty extender, then the
// float32 voxels from vox_offset on.
void write_nifti_stream(std::ostream& out, z_stream* zs, nifti_image& nim, const Image& image, const std::string& path) {
  nifti_set_iname_offset(&nim, 1);
  nifti_1_header h;
  if (nifti_convert_nim2n1hdr(&nim, &h) != 0) throw InputError(path + ": cannot make a NIfTI-1 header");
  std::vector<char> head(static_cast<size_t>(nim.iname_offset), 0);
  std::memcpy(head.data(), &h, sizeof h);
  put(out, zs, head.data(), head.size(), false, path);
  const char* bytes = reinterpret_cast<const char*>(image.data.data());
  const size_t total = image.data.size() * sizeof(float), piece = size_t(1) << 24;
  for (size_t at = 0; at < total || at == 0; at += piece)
    put(out, zs, bytes + at, std::min(piece, total - at), at + piece >= total, path);
}

}  // namespace

void write_nifti(const std::string& path, const Image& image) {
  const bool gz = path.size() > 7 && path.substr(path.size() - 7) == ".nii.gz";
  if (!gz && (path.size() < 4 || path.substr(path.size() - 4) != ".nii"))
    throw InputError(path + ": write_nifti needs a .nii or .nii.gz name");
  const int64_t dims[8] = {3, image.dims[0], image.dims[1], image.dims[2], 1, 1, 1, 1};
  if (image.data.size() != size_t(dims[1] * dims[2] * dims[3]))
    throw InputError(path + ": the image has " + std::to_string(image.data.size()) + " values for " +
                     std::to_string(dims[1] * dims[2] * dims[3]) + " voxels");
  NimPtr nim(nifti_make_new_nim(dims, DT_FLOAT32, 0));
  if (!nim) throw InputError(path + ": cannot create a NIfTI image");
  nifti_dmat44 m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m.m[r][c] = image.affine(r, c);
  nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
  nim->sto_xyz = m;
  nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
  double dx, dy, dz, qfac;
  nifti_dmat44_to_quatern(m, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d, &nim->qoffset_x,
                          &nim->qoffset_y, &nim->qoffset_z, &dx, &dy, &dz, &qfac);
  nim->qfac = qfac;
  nim->dx = nim->pixdim[1] = dx;
  nim->dy = nim->pixdim[2] = dy;
  nim->dz = nim->pixdim[3] = dz;
  nim->qto_xyz = m;
  nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
  // through AtomicFile like every output (no partial file under any name), gzip by zlib here
  detail::AtomicFile file(path, true);
  z_stream zs{};
  if (gz && deflateInit2(&zs, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw InputError(path + ": cannot start gzip compression");
  struct End {
    z_stream* z;
    ~End() { if (z) deflateEnd(z); }
  } end{gz ? &zs : nullptr};
  write_nifti_stream(file.stream(), gz ? &zs : nullptr, *nim, image, path);
  file.commit();
}

}  // namespace vpm
