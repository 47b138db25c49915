#pragma once
// A patient's per-element result mapped back to the patient's own native space (paper 6.2,
// Fig. 10): through the patient's registered ball mesh, whose vertices sit in the common ball
// and whose point field `original_position` holds their native positions.
#include <map>
#include <string>
#include <vector>

#include "vpm/elements.hpp"
#include "vpm/image.hpp"
#include "vpm/mesh.hpp"
#include "vpm/statistics.hpp"

namespace vpm {

/// The patient's native mesh (vertices = original_position of `registered`) with the per-element
/// `values` (one per element, e.g. z) as fields: point field `name` at each vertex's ball
/// position, cell field `name` at each tet's ball centroid. InputError when `registered` has no
/// original_position field.
TetMesh native_mesh_with_values(const TetMesh& registered, const CanonicalElements& elements,
                                const std::vector<std::vector<double>>& values, const std::vector<std::string>& names);

/// Per-element `values` pushed onto the voxel grid of `grid` (same dims and affine): each voxel
/// centre is located in the native mesh, carried into the ball by the same barycentric
/// combination of the ball vertices, and takes the value of the element there; voxels outside
/// the native mesh get `outside`. Runs on the host threads.
Image native_volume(const TetMesh& registered, const CanonicalElements& elements, const std::vector<double>& values,
                    const Image& grid, float outside = 0.0f);

/// A focus cluster measured in the patient's native space.
struct NativeFocus {
  int id = 0;                ///< FocusCluster::id
  long voxels = 0;           ///< voxels of the cluster's map-back volume
  double volume_mm3 = 0;     ///< voxels x voxel volume
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< world mm (NaN when no voxel)
  double peak_z = 0;         ///< FocusCluster::peak_z
  int label = 0;             ///< most frequent label under the cluster (0: no label image or none)
  double label_fraction = 0; ///< share of the cluster's voxels carrying `label`
  std::string region;        ///< `label`'s name in the label table ("" when none is given or lists it)
  double p_family = -1;      ///< FocusCluster::p_family (-1: not known)
};

/// Per cluster of `comparison` (foci_volume = native_volume of its cluster ids, on the patient's
/// image grid): voxel count, volume in mm^3, world centroid, peak z, and with `labels` (an atlas
/// image in the same native space; read at each voxel centre, nearest voxel) its main region,
/// named from `names` (vpm/label_names.hpp) when given.
std::vector<NativeFocus> native_foci(const Image& foci_volume, const Comparison& comparison, const Image* labels = nullptr,
                                     const std::map<int, std::string>* names = nullptr);

/// Writes `foci` as TSV: focus voxels volume_mm3 centroid_x centroid_y centroid_z peak_z label
/// label_fraction region p_family (region empty when unnamed, p_family NA when not known; a
/// region name's tabs and line breaks written as spaces). Atomic; InputError naming the path
/// when it cannot be written.
void write_native_foci(const std::string& tsv_path, const std::vector<NativeFocus>& foci);

}  // namespace vpm
