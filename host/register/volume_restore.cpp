// ---- volume restoration after the flow ----
#include "register/registration_steps.hpp"

#include <algorithm>
#include <cmath>

#include "vpm/locate.hpp"
#include "vpm/topology.hpp"
#include "vpm/polish.hpp"

namespace vpm {

RegistrationRestore restore_volumes(Device& dev, const RestoreMesh& mesh, Points& after,
                                    const std::vector<char>& landmark_vertex, const Points& landmarks_final,
                                    const std::vector<VolumeHold>& holds, const RegistrationOptions& opt) {
  const Tets& tets = mesh.tets;
  PolishOptions vo;
  vo.place = opt.restore_polish;
  vo.topology = &mesh.topology;
  vo.boundary = MapBoundary::slide;
  vo.pinned = landmark_vertex;
  vo.holds = holds;
  vo.iterations = opt.restore_iterations;  // scaled by polish_iterations_for: the same reach on finer meshes
  vo.rounds = opt.restore_rounds;
  vo.min_gain = opt.restore_min_gain;
  // Each landmark inside a tet is held where it is: as an anchor (its barycentric combination of
  // the tet's vertices fixed) when the tet's vertices are interior and not landmark vertices;
  // otherwise by pinning the tet's four vertices. Pinned vertices cannot be anchor vertices, so
  // a tet that shares a vertex with a pinned one is pinned too (repeated until none changes).
  const TetLocator locator(after, tets, mesh.topology);
  std::vector<Location> held;
  for (Eigen::Index i = 0; i < landmarks_final.rows(); ++i) {
    const Location l = locator.locate(landmarks_final.row(i).transpose());
    if (l.tet >= 0 && l.min_bary >= -1e-9) held.push_back(l);
  }
  const std::vector<char>& boundary = mesh.topology.boundary_vertex;
  std::vector<char> pin_tet(held.size(), 0);
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t i = 0; i < held.size(); ++i) {
      if (pin_tet[i]) continue;
      for (int k = 0; k < 4; ++k) {
        const auto v = static_cast<size_t>(tets(held[i].tet, k));
        if (boundary[v] || vo.pinned[v]) pin_tet[i] = 1;
      }
      if (pin_tet[i]) {
        for (int k = 0; k < 4; ++k) vo.pinned[static_cast<size_t>(tets(held[i].tet, k))] = 1;
        changed = true;
      }
    }
  }
  RegistrationRestore r;
  for (size_t i = 0; i < held.size(); ++i) {
    const Location& l = held[i];
    if (!pin_tet[i]) {
      VolumeAnchor a;
      for (int k = 0; k < 4; ++k) {
        a.vertices[static_cast<size_t>(k)] = tets(l.tet, k);
        a.weights[static_cast<size_t>(k)] = l.bary[k];
      }
      vo.anchors.push_back(a);
    }
  }
  r.anchored_landmarks = static_cast<int>(vo.anchors.size());
  r.held_points = static_cast<int>(holds.size());
  for (char c : vo.pinned) r.pinned_vertices += c != 0;
  const VolumeMapResult vm = polish_volumes(dev, mesh.before, tets, after, vo);
  r.vertex_mean_abs_dev_before = vm.initial_vertex_mean_abs_dev;
  r.tet_mean_abs_dev_before = vm.initial_tet_mean_abs_dev;
  r.vertex_mean_abs_dev = vm.final_vertex_mean_abs_dev;
  r.tet_mean_abs_dev = vm.final_tet_mean_abs_dev;
  r.rounds = static_cast<long>(vm.rounds.size());
  r.placement = vm.placement;
  return r;
}

}  // namespace vpm
