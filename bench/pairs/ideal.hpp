#pragma once
// The ideal registration of the benchmark of registered pairs: the subject is Colin27 read
// through a known deformation, so the registration a perfect method would find is known too. Each subject vertex (native position
// y) goes where Colin27's ball map puts the Colin27 point it shows, pull(y); surface vertices
// go radially onto the sphere. Its overlap is what the two meshes and maps allow, and the
// distance of the actual registration to it is the registration's error. It is not a
// volume-preserving registration: the two meshes' surfaces differ by about a voxel, and near
// them (at paper size most tets touch the surface) its tets are squeezed or stretched by tens of
// percent (docs/register.md, "Two Dice measures"; bench/results/register_faster_steps_ideal/).
#include <functional>
#include <string>

#include <Eigen/Core>

#include "pairs/overlap.hpp"
#include "vpm/device.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh.hpp"
#include "vpm/metrics.hpp"

namespace vpm::bench {

struct IdealRegistration {
  Points ball;        ///< the subject's vertices in the ball, ideally registered (n x 3)
  long outside = 0;   ///< vertices whose pull(y) fell outside Colin27's mesh (nearest tet used)
  long boundary = 0;  ///< the subject's surface vertices, put on the sphere (radially)
};

/// `subject` and `tmpl`: the two ball maps (with their native positions); `pull`: subject native
/// position -> Colin27 native position (demo_deformation; the identity for --ceiling).
IdealRegistration ideal_registration(const TetMesh& subject, const TetMesh& tmpl,
                                     const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& pull);

/// The ideal registration measured like the actual one.
struct IdealReport {
  IdealRegistration ideal;
  Overlap overlap;     ///< "after": through the ideal registration
  MapMetrics metrics;  ///< its volume distortion against the subject's map before registration
  /// |actual - ideal| over the subject's vertices (ball units): the registration's error
  double error_mean = 0, error_p90 = 0, error_max = 0;
  Eigen::VectorXd error;  ///< per subject vertex
};

/// Builds the ideal registration and measures it: `overlap_of(ball)` is the benchmark's overlap of
/// the subject registered to `ball`; `registered` the actual registration's vertices.
IdealReport measure_ideal(Device& device, const TetMesh& subject, const TetMesh& tmpl, const Points& registered,
                          const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& pull,
                          const std::function<Overlap(const Points&)>& overlap_of);

/// {"held_out": [{"label", "dice_image", "dice_subject"}], "landmark_regions_mean_dice_image", "vertex_volume_ratio",
///  "tet_volume_ratio", "inverted_tets", "outside_vertices", "error_to_ideal": {"mean", "p90", "max"}}
Json to_json(const IdealReport& report, const std::vector<int>& evaluated);

/// Two summary lines for the benchmark's table.
std::string ideal_summary(const IdealReport& report);

}  // namespace vpm::bench
