#pragma once
// The pipeline `vpm demo` runs, shared with the benchmark of registered pairs (bench/pairs.cpp):
// two subjects meshed and mapped to the ball, the second registered to the first by the
// centroids of their atlas regions (register_to_template), the held-out regions left out.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vpm/ball_map.hpp"
#include "vpm/dense_registration.hpp"
#include "vpm/device.hpp"
#include "vpm/image.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/metrics.hpp"
#include "vpm/registration.hpp"
#include "vpm/template_registration.hpp"

namespace vpm::cli {

/// The AAL regions whose overlap the demo measures (Caudate_L/R, Thalamus_L/R): held out of the
/// landmarks and of the dense force.
extern const std::vector<int> kDemoHeldOut;

/// The world position of the centroid of a mask's voxels > 0 (InputError for an empty mask).
Eigen::Vector3d mask_centroid(const Image& mask);

/// AAL region names by label from Debian's aal.nii.txt ("ID NAME CODE" lines; empty if unreadable).
using RegionNames = std::map<int, std::string>;
RegionNames aal_names(const std::string& path);
/// The region's name, or "label L".
std::string name_of(const RegionNames& names, int label);

/// One subject meshed and mapped.
struct DemoSubject {
  BallMap map;
  int vertices = 0, tets = 0;
  double min_dihedral_deg = 0, mesh_seconds = 0, map_seconds = 0;
};
Json to_json(const DemoSubject& s);

/// Meshes `image` with `atlas`'s labels, maps it to the ball and writes NAME.vtu, NAME_ball.vtu
/// and NAME_map.json in `out` (a map short of its tolerance is a warning line, not an error).
DemoSubject mesh_and_map(Device& dev, const Image& image, const Image& atlas, const MeshImageOptions& meshing,
                         const std::string& name, const std::filesystem::path& out);

/// The subject's ball registered to the template's.
struct DemoRegistration {
  RegistrationResult result;  ///< the landmark stage, with the final landmark errors
  DenseRegistrationResult dense;
  MapMetrics metrics;  ///< against the subject's map before registration
  Points registered;
  std::vector<int> tmpl_labels, subj_labels;  ///< the AAL label of each tet of the two maps
  std::vector<int> landmark_labels;           ///< the regions whose centroids were matched
  double seconds = 0;
};

/// Registers `subj` to `tmpl` by region centroids (kDemoHeldOut excluded from the landmarks and
/// the dense force), `flow` and `dense` the settings; writes landmarks.csv and targets.csv in `out`.
DemoRegistration register_demo_subject(Device& dev, const DemoSubject& tmpl, const DemoSubject& subj,
                                       const RegistrationOptions& flow, const DenseRegistrationOptions& dense,
                                       const Image& tmpl_image, const Image& subj_image,
                                       const std::filesystem::path& out);

/// The registration's JSON (registration_summary, landmarks, rotation, dense).
Json to_json(const DemoRegistration& r);

/// The summary's first lines: the two subjects side by side and the registration's line.
std::string subjects_summary(const std::string& heading, const DemoSubject& tmpl, const DemoSubject& subj,
                             const DemoRegistration& reg);

/// Writes the registered subject (`subject` at `reg.registered`) to `path` with its volume ratios
/// against the subject's map (point field registration_vertex_volume_ratio, cell field
/// registration_tet_volume_ratio) and `extra` point fields.
void write_registered(const std::string& path, const TetMesh& subject, const DemoRegistration& reg,
                      const std::vector<std::pair<std::string, Eigen::VectorXd>>& extra = {});

}  // namespace vpm::cli
