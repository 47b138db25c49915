#pragma once
// The surface part of `vpm demo`: the boundaries of the two meshed brains mapped to the sphere,
// the subject's registered onto Colin27's there by region-centroid landmarks and then by its
// mean curvature, the held-out regions' Dice measured on the sphere; and a cortical patch of
// Colin27's boundary mapped to the disk (docs/surfaces.md).
#include <filesystem>
#include <string>
#include <vector>

#include "demo_pipeline.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh.hpp"
#include "vpm/surface_map.hpp"
#include "vpm/surface_registration.hpp"

namespace vpm::cli {

/// The AAL regions whose overlap on the sphere the surface demo measures (Precentral_L/R,
/// Postcentral_L/R): held out of the landmarks.
extern const std::vector<int> kSurfaceHeldOut;

struct SurfaceDemo {
  SurfaceMapReport template_map, subject_map;      ///< the two boundaries to the sphere
  int landmarks = 0;                               ///< region centroids matched
  /// the subject on the sphere: by the landmarks, by them and then the curvature, by the
  /// curvature alone (its rotation search first)
  SurfaceRegistrationResult by_landmarks, by_curvature, by_curvature_alone;
  /// Dice of each held-out region on the sphere (kSurfaceHeldOut order): the maps as they are,
  /// after the landmarks, after the landmarks and the curvature, after the curvature alone
  std::vector<double> dice_before, dice_landmarks, dice_curvature, dice_curvature_alone;
  SurfaceMapReport patch_map;                      ///< the cortical patch to the disk
  bool patch_mapped = false;
  std::string patch_note;                          ///< why not, when not
};

/// Runs the surface demo on the native meshes `tmpl` and `subj` (cell field label), writing
/// colin27_sphere.vtp, subject_sphere.vtp, subject_sphere_registered.vtp, colin27_patch_disk.vtp
/// in `out`.
SurfaceDemo surface_demo(const TetMesh& tmpl, const TetMesh& subj, const std::filesystem::path& out);

Json to_json(const SurfaceDemo& d, const RegionNames& names);
/// The lines the demo prints.
std::string surface_summary(const SurfaceDemo& d, const RegionNames& names);

}  // namespace vpm::cli
