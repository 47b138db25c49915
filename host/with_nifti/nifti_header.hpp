#pragma once
// Private (with_nifti): checks a NIfTI file's header before nifti_clib allocates anything from
// it. nifti_clib trusts the header: it sizes the voxel buffer (and extension buffers) from it and
// silently replaces NaN or zero voxel sizes by 1 and NaN scale factors by 0. These checks refuse
// what a hostile or broken header can carry, with one line naming the file, the field and value.
#include <cstdint>
#include <string>

namespace vpm::detail {

/// The sizes a checked header declares.
struct NiftiHeaderSizes {
  std::int64_t nx = 1, ny = 1, nz = 1;  ///< voxels per axis (one 3-D volume)
  int bytes_per_voxel = 0;              ///< of the stored data type
  std::int64_t data_bytes = 0;          ///< nx * ny * nz * bytes_per_voxel
};

/// Reads only the fixed-size header of `path` (NIfTI-1 or -2, plain or gzip, either byte order)
/// and throws InputError unless: dim[0] is 1..7 and every used dim[i] >= 1, at most one volume
/// (dim[4..7] <= 1), each axis <= 100,000 and at most 2^31 voxels; a real scalar data type;
/// vox_offset finite and past the header; pixdim[1..3] finite (and > 0 where no sform gives the
/// affine); scl_slope/scl_inter finite; the sform rows (sform_code > 0) and the quaternion and
/// offsets (qform_code > 0) finite; and the file large enough for the declared data (plain
/// files: vox_offset + data bytes; gzip: at most 1032 times the compressed size, the deflate
/// limit). Then asks require_memory() for the voxels and their float copy.
NiftiHeaderSizes check_nifti_header(const std::string& path);

}  // namespace vpm::detail
