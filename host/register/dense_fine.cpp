// The restoration's holds and the fine steps of dense registration (register/dense_state.hpp,
// register/fine_step.hpp).
#include <cmath>

#include "register/dense_state.hpp"
#include "register/fine_step.hpp"
#include "vpm/device.hpp"
#include "vpm/format.hpp"
#include "vpm/geometry.hpp"
#include "vpm/locate.hpp"
#include "vpm/timing.hpp"

namespace vpm {

namespace {

/// One fine step (DenseRegistrationOptions::fine_iterations) on `x` (the vertices, then the
/// tracked landmarks, carried by the mesh): the mesh displacement of register/fine_step.hpp,
/// its folds untangled, then the volumes restored against `reference` with `pinned` vertices;
/// kept in `x` and `fit` when it lowers the mismatch without a fold.
DenseIteration fine_step(Device& dev, const DenseState& st, Points& x, const Points& reference,
                         const std::vector<char>& pinned, const RegistrationOptions& lo,
                         const DenseRegistrationOptions& o, Fit& fit) {
  const auto t0 = Clock::now();
  const Eigen::Index nv = st.reference.rows(), nl = x.rows() - nv;
  DenseIteration it;
  it.width = o.fine_sigma;
  it.centres = static_cast<int>(nv);
  const Points now = x.topRows(nv);
  const std::vector<Location> where = TetLocator(now, st.tets).locate_all(x.bottomRows(nl));
  const LocalSystems local = st.image->local_systems(fit.values, now, o.fine_sigma, 0);
  it.image_points = static_cast<long>(st.image->grid().rows());
  Points after = now + o.step * fine_displacement(local, now, st.tets, st.topology.boundary_vertex, o.fine_smoothness, 0.5 * o.fine_sigma);
  for (Eigen::Index v = 0; v < nv; ++v)
    if (st.topology.boundary_vertex[static_cast<size_t>(v)]) after.row(v).normalize();
  Eigen::VectorXd v1 = tet_volumes(dev, after, st.tets);
  it.folded = newly_inverted(st.v0, v1);
  if (it.folded > 0) untangle_flow_folds(dev, now, st.tets, after, st.topology.boundary_vertex, st.v0, v1, 2);
  Points lm(nl, 3);
  for (Eigen::Index l = 0; l < nl; ++l) {
    const Location& w = where[static_cast<size_t>(l)];
    lm.row(l) = x.row(nv + l);
    if (w.tet < 0) continue;
    Eigen::RowVector3d p = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) p += w.bary[k] * after.row(st.tets(w.tet, k));
    lm.row(l) = p;
  }
  restore_volumes(dev, {reference, st.tets, st.topology}, after, pinned, lm, restore_holds(st, after, o), lo);
  v1 = tet_volumes(dev, after, st.tets);
  it.max_move = (after - now).rowwise().norm().maxCoeff();
  Fit next(st, after);
  it.agreement = next.agreement;
  it.mismatch = next.mismatch;
  it.accepted = newly_inverted(st.v0, v1) == 0 && next.better_than(fit, st.force);
  if (it.accepted) {
    x.topRows(nv) = after;
    x.bottomRows(nl) = lm;
    fit = std::move(next);
  }
  it.seconds = seconds_since(t0);
  return it;
}

}  // namespace

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


void fine_steps(Device& dev, const DenseState& st, Points& x, const Points& reference, const std::vector<char>& pinned,
                const RegistrationOptions& lo, const DenseRegistrationOptions& o, Fit& fit, DenseRegistrationResult& r) {
  for (int i = 0; i < o.fine_iterations; ++i) {
    if (o.deadline.passed()) {
      r.time_budget_spent = true;
      break;
    }
    r.iterations.push_back(fine_step(dev, st, x, reference, pinned, lo, o, fit));
    const DenseIteration& it = r.iterations.back();
    if (o.progress)
      o.progress(strprintf("fine step %d (sigma %.3g): image mismatch %.4f, %s%.2f s", i + 1, o.fine_sigma,
                           it.mismatch, it.accepted ? "" : "rejected, ", it.seconds));
    if (!it.accepted) break;
  }
  r.agreement_after = fit.agreement;
  r.mismatch_after = fit.mismatch;
}

}  // namespace vpm
