// The restoration's holds of dense registration (register/dense_state.hpp): the image's edges.
#include <cmath>

#include "register/dense_state.hpp"
#include "vpm/locate.hpp"

namespace vpm {

// The subject's gradient at each grid point, in template standard deviations per ball unit, is
// the direction it is held along (sum |direction|^2 = weight x tets).
std::vector<VolumeHold> image_holds(const DenseState& st, const Points& ball, double weight) {
  const Points g = st.image->gradients(st.image->subject_values(ball));
  const Points& grid = st.image->grid();
  const TetLocator locator(ball, st.tets);
  std::vector<VolumeHold> holds;
  double sum = 0;
  for (Eigen::Index p = 0; p < grid.rows(); ++p) {
    if (g.row(p).squaredNorm() == 0) continue;
    const Location l = locator.locate(grid.row(p).transpose());
    if (l.tet < 0 || !l.inside()) continue;
    VolumeHold h;
    for (int k = 0; k < 4; ++k) {
      h.vertices[static_cast<size_t>(k)] = st.tets(l.tet, k);
      h.weights[static_cast<size_t>(k)] = l.bary[k];
    }
    h.direction = g.row(p).transpose();
    sum += h.direction.squaredNorm();
    holds.push_back(h);
  }
  const double scale = sum > 0 ? std::sqrt(weight * static_cast<double>(st.tets.rows()) / sum) : 0.0;
  for (VolumeHold& h : holds) h.direction *= scale;
  return holds;
}

std::vector<VolumeHold> restore_holds(const DenseState& st, const Points& ball, const DenseRegistrationOptions& o) {
  return st.image && o.restore_image_weight > 0 ? image_holds(st, ball, o.restore_image_weight)
                                                : std::vector<VolumeHold>{};
}


}  // namespace vpm
