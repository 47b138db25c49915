#pragma once
// Atlas labels of the image layer: the per-label report of mesh_image().
#include "vpm/image.hpp"
#include <map>

#include "vpm/mesh.hpp"
#include "vpm/mesh_image_report.hpp"

namespace vpm::detail {

/// Labels `mesh` from `atlas` (label_mesh) and returns, for every non-zero atlas label, its
/// tets and volume in the mesh and its voxels and their volume in the atlas.
std::map<int, LabelVolume> label_report(TetMesh& mesh, const Image& atlas);

}  // namespace vpm::detail
