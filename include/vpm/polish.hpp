#pragma once
// The polish of a map's local volumes on its own (the map layer's second public stage; the
// volume map runs the same rounds after its Moser rounds): Gauss-Newton steps on the per-tet
// volumes against a reference mesh, min over dx of sum_t (1 - V_t(x + dx) / m_t)^2 linearised
// and solved by early-stopped CGLS from dx = 0 (the minimum-norm start is the regularisation),
// with some vertices pinned, some material points anchored and some held along a direction;
// every step fold-checked, untangled locally or halved, and kept only while it lowers the tet
// distortion. Registration uses it to give back the volume that linear tets lost under its
// divergence-free flow (RegistrationOptions::restore_volumes).
#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "vpm/mesh.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"
#include "vpm/volume_map.hpp"

namespace vpm {

class Device;

/// A material point the polish keeps in place: p = sum_k weights[k] x_(vertices[k]) (e.g.
/// barycentric coordinates in a tet). Every polish direction dx satisfies
/// sum_k weights[k] dx_(vertices[k]) = 0 (the orthogonal projection onto that constraint), the
/// polish's steps are x + s dx, and untangling leaves the four vertices alone, so p stays where it
/// is to rounding while its vertices move.
struct VolumeAnchor {
  std::array<int, 4> vertices{};
  std::array<double, 4> weights{};
};

/// A material point p = sum_k weights[k] x_(vertices[k]) that the polish should not move along
/// `direction` (registration: an image edge at p, its gradient scaled by the hold's weight): the
/// least-squares row direction . sum_k weights[k] dx_(vertices[k]) = 0 joins the polish's
/// tet-volume rows, so a step that slides p across the edge costs |direction|^2 |move|^2, and
/// motion along the edge or where nothing is held stays free.
struct VolumeHold {
  std::array<int, 4> vertices{};
  std::array<double, 4> weights{};
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
};

struct PolishOptions {
  /// Boundary vertices slide on the unit sphere (slide) or stay (fixed); automatic = slide.
  MapBoundary boundary = MapBoundary::slide;
  int rounds = 8;       ///< at most this many steps
  /// Steps end once one lowers the tet mean |r-1| by less than this fraction of it.
  double min_gain = 0.01;
  /// CGLS iterations per step at up to 30,000 tets, scaled by polish_iterations_for above, so
  /// that a step reaches as far in the ball on finer meshes.
  int iterations = 60;
  /// Vertices that never move: n entries (1 = pinned) or empty. Honoured by the steps and the
  /// untangling.
  std::vector<char> pinned;
  /// Material points that never move (VolumeAnchor); an anchor's vertices must be in range,
  /// interior and not pinned, its weights not all zero. Anchors may share vertices: their
  /// constraints are then projected jointly. Registration anchors its landmarks this way: 3
  /// constraints per landmark instead of its tet's 4 pinned vertices (12).
  std::vector<VolumeAnchor> anchors;
  /// Soft holds (VolumeHold) added to the least squares (vertices in range).
  std::vector<VolumeHold> holds;
  /// The topology of `tets` (vpm/topology.hpp) when the caller has built it (it must be
  /// tet_topology(n, tets) of these tets and outlive the call); nullptr: built here. Callers
  /// that polish the same mesh again and again (registration's restorations) build it once.
  const TetTopology* topology = nullptr;
  /// Where the CGLS runs: automatic = the OpenCL kernels (kernels/polish.cl, holds as rows after
  /// the tets') on GPUs, the host threads otherwise; device forces the kernels on any OpenCL
  /// device.
  ExecutionPlace place = ExecutionPlace::automatic;
  /// Local untangling of steps that fold (theta 0.5, two rings, boundary and pinned fixed)
  /// before the step is halved.
  bool local_untangle = true;
  Deadline deadline{};  ///< checked before every step (stop_reason "time_budget")
  /// Called with one line per step (progress display); may be empty.
  std::function<void(const std::string&)> progress;
};

/// `base` CGLS iterations at up to 30,000 tets, times cbrt(tets / 30,000) above: a CGLS
/// iteration reaches one more ring of tets, so the same reach in ball units needs more of them
/// on a finer mesh. The one place this scaling lives (polish_volumes, the volume map's polish
/// far from its tolerance).
int polish_iterations_for(int base, long long tets);

/// Polishes `x` (n x 3, in: a fold-free map of the mesh; out: the polished map) against the
/// reference mesh (`reference` n x 3, `tets` m x 4 positively oriented on it), whose tet
/// volumes scaled to x's total are the targets. Returns the rounds (kind "polish") and the
/// distortion before and after (VolumeMapResult, stop_reason "polish_only" or "time_budget").
/// Throws InputError on inconsistent sizes or bad pins, anchors or holds; NumericalError when x
/// is folded and local untangling cannot repair it.
VolumeMapResult polish_volumes(Device& device, const Points& reference, const Tets& tets, Points& x,
                               const PolishOptions& options = {});

}  // namespace vpm
