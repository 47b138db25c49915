#pragma once
// 3-D images (NIfTI-1/2 and FreeSurfer MGH/MGZ volumes): grid, voxel -> world affine, intensities
// as float.
#include <Eigen/Dense>
#include <array>
#include <functional>
#include <cstddef>
#include <string>
#include <vector>

namespace vpm {

/// A scalar 3-D image on a regular voxel grid.
struct Image {
  std::array<int, 3> dims{0, 0, 0};        ///< voxels along i, j, k
  std::array<double, 3> spacing{1, 1, 1};  ///< voxel size along i, j, k in mm (column norms of the affine)
  /// Voxel index (i, j, k, 1) -> world millimetres (x, y, z, 1). Voxel centres sit at integer
  /// indices.
  Eigen::Matrix4d affine = Eigen::Matrix4d::Identity();
  /// Where the affine came from: "sform", "qform" or "pixdim" (neither code set: scaling only),
  /// or "mgh" (an MGH header's direction cosines, voxel sizes and centre).
  std::string affine_source = "pixdim";
  /// dims[0]*dims[1]*dims[2] values, i fastest: value(i,j,k) = data[i + dims[0]*(j + dims[1]*k)].
  /// Scaled by scl_slope/scl_inter when the file sets them.
  std::vector<float> data;
  std::string path;  ///< the file it was read from (for messages), may be empty

  size_t size() const { return size_t(dims[0]) * dims[1] * dims[2]; }
  size_t index(int i, int j, int k) const { return size_t(i) + size_t(dims[0]) * (size_t(j) + size_t(dims[1]) * k); }
  float at(int i, int j, int k) const { return data[index(i, j, k)]; }
  /// World position (mm) of a (possibly fractional) voxel index.
  Eigen::Vector3d to_world(const Eigen::Vector3d& ijk) const {
    return affine.topLeftCorner<3, 3>() * ijk + affine.topRightCorner<3, 1>();
  }
  /// Voxel index (fractional) of a world position.
  Eigen::Vector3d to_voxel(const Eigen::Vector3d& xyz) const {
    return affine.topLeftCorner<3, 3>().inverse() * (xyz - affine.topRightCorner<3, 1>());
  }
};

/// Reads a NIfTI-1 or NIfTI-2 image (.nii, .nii.gz, or a .hdr/.img pair) with nifti_clib.
/// A 4-D file with one volume (dim[4] == 1) is accepted as 3-D. The affine is the sform when
/// sform_code > 0, else the qform when qform_code > 0, else the pixdim scaling.
/// Throws InputError("PATH: what") when the file is missing or unreadable, is not NIfTI, is
/// truncated (e.g. a cut gzip stream), has more than one volume (4-D), has a complex/RGB data
/// type, or when vpm was built without nifti_clib.
Image read_nifti(const std::string& path);

/// Reads a FreeSurfer MGH volume: `.mgh` (raw) or `.mgz` / `.mgh.gz` (gzip). The voxel -> world
/// (scanner RAS, mm) affine is FreeSurfer's vox2ras, as nibabel's MGHHeader.get_affine() gives it:
/// columns Mdc_j x delta_j, translation c_ras - M (dims / 2); a header without valid RAS
/// (goodRASflag <= 0) gets FreeSurfer's default (coronal, 1 mm, centred). Data types uchar,
/// short, int and float; one frame. Throws InputError("PATH: what") for a file that is missing,
/// not MGH (version != 1), truncated (fewer voxel bytes than the header says: checked as the
/// data is read, before the image is allocated), has several frames, another data type, or
/// sizes that are not positive.
Image read_mgh(const std::string& path);

/// True when `path` ends in .mgh, .mgz or .mgh.gz (any case): read_image() reads it as MGH.
bool is_mgh_path(const std::string& path);

/// Reads an image by its name: read_mgh() for .mgh/.mgz/.mgh.gz, read_nifti() otherwise. What
/// every command that takes an image calls.
Image read_image(const std::string& path);

/// Writes `image` as NIfTI-1 (float32, sform and qform set from `image.affine`; `.nii.gz`
/// compresses). Used for tests and fixtures. Throws InputError when it cannot write.
void write_nifti(const std::string& path, const Image& image);

/// Interpolation for resample_image: nearest voxel (labels) or trilinear (intensities).
enum class Interpolation { nearest, linear };

/// `image` read at world position `x` (mm): the nearest voxel or trilinear between the eight
/// around it; voxels outside the grid count as 0.
float sample_image(const Image& image, const Eigen::Vector3d& x, Interpolation interpolation);

/// Whether world position `x` lies within the voxel grid of `image` (within half a voxel of
/// the outermost voxel centres).
bool inside_grid(const Image& image, const Eigen::Vector3d& x);

/// An image on the grid of `image` (same dims and affine) whose value at each voxel centre x
/// (world mm) is `image` read at pull(x): `pull` maps output world positions to input world
/// positions, so resampling through the inverse of a deformation applies the deformation.
/// Positions outside the input grid read 0. Runs on the host threads available.
Image resample_image(const Image& image, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& pull,
                     Interpolation interpolation);

}  // namespace vpm
