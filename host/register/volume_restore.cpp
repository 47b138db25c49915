// ---- volume restoration after the flow ----
#include "register/registration_steps.hpp"
#include "vpm/locate.hpp"
#include "vpm/volume_map.hpp"

namespace vpm {

RegistrationRestore restore_volumes(Device& dev, const Points& before, const Tets& tets, Points& after,
                                    const std::vector<char>& landmark_vertex, const Points& landmarks_final) {
  VolumeMapOptions vo;
  vo.polish_only = true;
  vo.boundary = MapBoundary::slide;
  vo.pinned = landmark_vertex;
  const TetLocator locator(after, tets);
  for (Eigen::Index i = 0; i < landmarks_final.rows(); ++i) {
    const Location l = locator.locate(landmarks_final.row(i).transpose());
    if (l.tet >= 0 && l.min_bary >= -1e-9)
      for (int k = 0; k < 4; ++k) vo.pinned[static_cast<size_t>(tets(l.tet, k))] = 1;
  }
  RegistrationRestore r;
  for (char c : vo.pinned) r.pinned_vertices += c != 0;
  const VolumeMapResult vm = volume_preserving_map(dev, before, tets, after, vo);
  r.vertex_mean_abs_dev_before = vm.initial_vertex_mean_abs_dev;
  r.tet_mean_abs_dev_before = vm.initial_tet_mean_abs_dev;
  r.vertex_mean_abs_dev = vm.final_vertex_mean_abs_dev;
  r.tet_mean_abs_dev = vm.final_tet_mean_abs_dev;
  r.rounds = static_cast<long>(vm.rounds.size());
  return r;
}

}  // namespace vpm
