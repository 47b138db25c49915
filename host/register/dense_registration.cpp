// Dense registration (vpm/dense_registration.hpp): the landmark registration, then flows that
// pull region boundaries onto the template's, then the exact landmark correction and the
// volume restoration (the report's JSON: dense_report.cpp).
#include "vpm/dense_registration.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>

#include "vpm/format.hpp"
#include "register/dense_force.hpp"
#include "register/dense_image_force.hpp"
#include "register/dense_refine.hpp"
#include "register/dense_state.hpp"
#include "register/rbf_gram.hpp"
#include "register/registration_steps.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/labels.hpp"
#include "vpm/locate.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace {

void check_dense(const Tets& tets, const std::vector<int>& labels, const Tets& ttets,
                 const std::vector<int>& tlabels, const DenseRegistrationOptions& o) {
  auto bad = [](const std::string& what) { throw InputError("dense registration: " + what); };
  if (labels.size() != static_cast<size_t>(tets.rows()))
    bad(std::to_string(labels.size()) + " labels for " + std::to_string(tets.rows()) + " tets");
  if (tlabels.size() != static_cast<size_t>(ttets.rows()))
    bad("template: " + std::to_string(tlabels.size()) + " labels for " + std::to_string(ttets.rows()) + " tets");
  if (o.iterations < 0) bad("iterations must be >= 0");
  if (o.widths.empty()) bad("no widths");
  for (double w : o.widths)
    if (!(w > 0) || w > 2) bad("widths must lie in (0, 2]");
  if (!(o.step > 0 && o.step <= 1)) bad("step must lie in (0, 1]");
  if (!(o.centre_spacing >= 0.25) || !(o.smoothing > 0) || !(o.ridge >= 0)) bad("invalid smoothing options");
  if (!(o.fit_tolerance > 0 && o.fit_tolerance < 1)) bad("the fit tolerance must lie in (0, 1)");
  if (o.advect_steps < 1 || o.agreement_grid < 4) bad("advect steps >= 1 and agreement grid >= 4 required");
  const DenseRefineOptions& r = o.refine;
  if (r.iterations < 0 || r.memory < 1 || r.memory > 64 || !(r.volume_weight >= 0) || !(r.smoothing_mm >= 0) ||
      r.smoothing_mm > 20 || !(r.min_gain >= 0 && r.min_gain < 1))
    bad("invalid image refinement options");
  if (r.iterations > 0 && (o.force == DenseForce::labels || o.iterations == 0))
    bad("the image refinement follows dense iterations with an image force (image or both)");
  if (o.force != DenseForce::labels &&
      (!(o.image_grid == 0 || (o.image_grid >= 4 && o.image_grid <= 512)) || !(o.image_smoothing >= 0)))
    bad("the image force needs 0 (automatic) or 4 to 512 grid cells and a smoothing >= 0");
}

/// The symmetric closest-point matches of the region boundaries with the subject at `ball`;
/// their count and mean length go to `it`.
BoundaryMatches boundary_matches(const DenseState& st, const Points& ball, DenseIteration& it) {
  BoundaryMatches m = closest_matches(region_surface(ball, st.faces), st.templ);
  it.matches = static_cast<long>(m.at.rows());
  it.mean_match_distance = m.mean_distance;
  return m;
}

/// The force as local least-squares systems at `centres` (fit_divfree_weighted):
/// the image's structure tensors and mismatch vectors scaled to a mean trace of 3 (so a centre of
/// average texture weighs as much as one full of boundary matches), the boundary matches as
/// isotropic systems of their mass (smooth_matches); `both` averages the two.
LocalSystems dense_systems(const DenseState& st, const Points& ball, const Fit& fit, const Points& centres,
                           double width, const DenseRegistrationOptions& o, DenseIteration& it) {
  const Eigen::Index nc = centres.rows();
  LocalSystems labels, image;
  if (st.force != DenseForce::image) {
    Eigen::VectorXd mass;
    labels.b = smooth_matches(boundary_matches(st, ball, it), centres, o.smoothing * width, &mass);
    for (Eigen::Index c = 0; c < nc; ++c) labels.a.push_back(mass(c) * Eigen::Matrix3d::Identity());
  }
  if (st.force != DenseForce::labels) {
    image = st.image->local_systems(fit.values, centres, o.smoothing * width, o.image_smoothing * width);
    it.image_points = static_cast<long>(st.image->grid().rows());
    double trace = 0;
    for (const Eigen::Matrix3d& a : image.a) trace += a.trace();
    const double scale = trace > 0 ? 3.0 * static_cast<double>(nc) / trace : 0.0;
    for (Eigen::Matrix3d& a : image.a) a *= scale;
    image.b *= scale;
    // reported: the mean length of the translations the centres ask for on their own (each
    // system alone, + eps I: eps = kTextureFloor x the mean trace, here 3)
    double length = 0;
    for (Eigen::Index c = 0; c < nc; ++c)
      length += (image.a[static_cast<size_t>(c)] + 3 * ImageForce::kTextureFloor * Eigen::Matrix3d::Identity())
                    .ldlt().solve(image.b.row(c).transpose()).norm();
    it.mean_translation = nc > 0 ? length / static_cast<double>(nc) : 0.0;
  }
  if (st.force == DenseForce::labels) return labels;
  if (st.force == DenseForce::image) return image;
  for (Eigen::Index c = 0; c < nc; ++c) image.a[static_cast<size_t>(c)] = 0.5 * (image.a[static_cast<size_t>(c)] + labels.a[static_cast<size_t>(c)]);
  image.b = 0.5 * (image.b + labels.b);
  return image;
}

/// What the iterations of one level share: the width, the field's centres and their Gram matrix.
struct Level {
  double width = 0;
  Points centres;
  SparseGram gram;
  Level(double w, const DenseRegistrationOptions& o)
      : width(w), centres(ball_grid(o.centre_spacing * w)), gram(sparse_gram(centres, RbfKernel::Tangent, 1 / (w * w))) {}
};

/// One dense iteration at `level` on `x` (the vertices, then the tracked landmarks): kept in `x`
/// and `fit` when it improves the fit without leaving a fold.
DenseIteration dense_step(Device& dev, const DenseState& st, Points& x, const Level& level,
                          const DenseRegistrationOptions& o, Fit& fit, double& max_normal) {
  const auto t0 = Clock::now();
  const Eigen::Index nv = st.reference.rows();
  const double width = level.width;
  const Points& centres = level.centres;
  DenseIteration it;
  it.width = width;
  it.centres = static_cast<int>(centres.rows());
  RbfFitOptions fo;
  fo.kernel = RbfKernel::Tangent;
  fo.lambda = 1 / (width * width);
  fo.ridge = o.ridge;
  fo.tolerance = o.fit_tolerance;
  const Points ball = x.topRows(nv);
  DivFreeField field =
      fit_divfree_weighted(centres, level.gram, dense_systems(st, ball, fit, centres, width, o, it), fo);
  field.coefficients *= o.step;
  max_normal = std::max(max_normal, max_normal_velocity(dev, {field}, 1000));
  Points y = x;
  advect(dev, y, {field}, o.advect_steps);
  Points after = y.topRows(nv);
  for (Eigen::Index v = 0; v < nv; ++v)
    if (st.topology.boundary_vertex[static_cast<size_t>(v)]) after.row(v).normalize();
  for (Eigen::Index l = nv; l < y.rows(); ++l)  // landmarks on the sphere stay on it exactly
    if (std::abs(x.row(l).norm() - 1) <= 1e-9) y.row(l).normalize();
  Eigen::VectorXd v1 = tet_volumes(dev, after, st.tets);
  it.folded = newly_inverted(st.v0, v1);
  // Untangled against the positions before this step, not the map before registration: the
  // latter pulls the freed rings back towards the unregistered shape, which undid whole patches
  // of the registration (moves of 0.06 ball units around one folded tet) and ended the finest
  // level at its second iteration (bench/results/register_untangle_systems/).
  if (it.folded > 0) {
    const Points before = x.topRows(nv);
    untangle_flow_folds(dev, before, st.tets, after, st.topology.boundary_vertex, st.v0, v1, 2);
  }
  it.max_move = (after - x.topRows(nv)).rowwise().norm().maxCoeff();
  Fit now(st, after);
  it.agreement = now.agreement;
  it.mismatch = now.mismatch;
  it.accepted = newly_inverted(st.v0, v1) == 0 && now.better_than(fit, st.force);
  if (it.accepted) {
    x.topRows(nv) = after;
    x.bottomRows(x.rows() - nv) = y.bottomRows(x.rows() - nv);
    fit = std::move(now);
  }
  it.seconds = seconds_since(t0);
  return it;
}

/// Up to `n` dense iterations at `level` from `fit`, ending at the first rejected one or when the
/// deadline passes (r.time_budget_spent).
void level_iterations(Device& dev, const DenseState& st, Points& x, const Level& level, int n,
                      const DenseRegistrationOptions& o, Fit& fit, DenseRegistrationResult& r) {
  for (int i = 0; i < n; ++i) {
    if (o.deadline.passed()) {
      r.time_budget_spent = true;
      return;
    }
    r.iterations.push_back(dense_step(dev, st, x, level, o, fit, r.max_normal_velocity));
    const DenseIteration& it = r.iterations.back();
    if (o.progress)
      o.progress(strprintf("dense iteration %d (width %.3g): label agreement %.4f, %s%.2f s",
                           static_cast<int>(r.iterations.size()), level.width, it.agreement,
                           it.accepted ? "" : "rejected, ", it.seconds));
    if (!it.accepted) return;
  }
}

/// The dense iterations from `fit` (that of the landmark registration), coarse to fine; a level
/// ends at its first rejected iteration. `fit` ends as that of x. Returns the finest level when
/// it ran (its Gram matrix is the costliest to build: the restore cycles reuse it).
std::optional<Level> dense_iterations(Device& dev, const DenseState& st, Points& x, const DenseRegistrationOptions& o,
                                      Fit& fit, DenseRegistrationResult& r) {
  const int levels = static_cast<int>(o.widths.size());
  std::optional<Level> finest;
  for (int l = 0; l < levels && !r.time_budget_spent; ++l) {
    const int n = o.iterations / levels + (l < o.iterations % levels ? 1 : 0);
    if (n == 0) continue;
    Level level(o.widths[static_cast<size_t>(l)], o);
    level_iterations(dev, st, x, level, n, o, fit, r);
    if (l == levels - 1) finest.emplace(std::move(level));
  }
  r.agreement_after = fit.agreement;
  r.mismatch_after = fit.mismatch;
  return finest;
}

DenseState dense_state(Device& dev, const Points& ball, const Tets& tets, const std::vector<int>& labels,
                       const Points& tball, const Tets& ttets, const std::vector<int>& tlabels,
                       const DenseRegistrationOptions& o, const DenseImages* images) {
  DenseState st{ball, tets, without_labels(labels, o.exclude_labels), tet_topology(static_cast<int>(ball.rows()), tets),
                {}, {}, {}, {}, {}, {}, nullptr, o.force};
  st.v0 = tet_volumes(dev, ball, tets);
  st.faces = region_faces(tets, st.labels);
  const std::vector<int> tl = without_labels(tlabels, o.exclude_labels);
  st.templ = region_surface(tball, region_faces(ttets, tl));
  const RegionSurface own = region_surface(ball, st.faces);
  std::set_intersection(own.labels.begin(), own.labels.end(), st.templ.labels.begin(), st.templ.labels.end(),
                        std::back_inserter(st.regions));
  st.grid = ball_grid(2.0 / o.agreement_grid);
  st.grid_templ = sample_labels(tball, ttets, tl, st.grid);
  if (o.force != DenseForce::labels && o.iterations > 0) {
    if (!images) throw InputError(std::string("dense registration: the ") + to_string(o.force) + " force needs images");
    const int cells = o.image_grid > 0 ? o.image_grid : dense_image_grid_cells(static_cast<long>(tets.rows()));
    st.image = std::make_unique<const ImageForce>(*images, tball, ttets, ball, tets, cells);
  }
  return st;
}

/// The final numbers: landmark errors against `targets`, inverted tets against the reference.
void finish(Device& dev, DenseRegistrationResult& r, const DenseState& st, const Points& work,
            const Points& landmarks_final, const Points& targets, bool refuse_folds) {
  const Eigen::VectorXd err = (landmarks_final - targets).rowwise().norm();
  r.landmark_rms_error = std::sqrt(err.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(err.size(), 1)));
  r.landmark_max_error = err.size() ? err.maxCoeff() : 0.0;
  r.inverted_tets = 0;
  const Eigen::VectorXd v1 = tet_volumes(dev, work, st.tets);
  for (Eigen::Index t = 0; t < v1.size(); ++t) r.inverted_tets += v1(t) <= 0;
  if (refuse_folds && newly_inverted(st.v0, v1) > 0) {
    std::ostringstream s;
    s << "dense registration folded the mesh: " << newly_inverted(st.v0, v1) << " of " << v1.size()
      << " tets inverted after the landmark correction";
    throw NumericalError(s.str());
  }
}

/// The image refinement of `work`; the landmarks `lm` move with their tets (the region centroids
/// are starting correspondences, about 0.01 ball units from the truth: held on their targets,
/// they cost held-out overlap).
DenseRefineReport refine_image(const DenseState& st, const DenseTemplate& templ, const DenseImages& images,
                               const Points& reference, Points& work, Points& lm, const DenseRefineOptions& o) {
  const std::vector<Location> at = TetLocator(work, st.tets, st.topology).locate_all(lm);
  const std::vector<char> fixed(st.topology.boundary_vertex.begin(), st.topology.boundary_vertex.end());
  DenseRefineReport rr = refine_against_image(images, templ, reference, st.tets, fixed, work, o);
  for (Eigen::Index l = 0; l < lm.rows(); ++l) {
    const Location& a = at[static_cast<size_t>(l)];
    Eigen::Vector3d q = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) q += a.bary[k] * work.row(st.tets(a.tet, k)).transpose();
    lm.row(l) = q.transpose();
  }
  return rr;
}

/// The landmark flow without rotation that takes the tracked landmarks `lm` back onto `targets`.
void correct_landmarks(Device& dev, Points& work, const Tets& tets, Points& lm, const Points& targets,
                       const RegistrationOptions& lo, DenseRegistrationResult& r) {
  const auto t0 = Clock::now();
  RegistrationOptions co = lo;
  co.rigid = false;
  co.restore_volumes = false;
  r.correction = register_landmarks(dev, work, tets, lm, targets, co);
  lm = r.correction->landmarks_final;
  r.max_normal_velocity = std::max(r.max_normal_velocity, r.correction->max_normal_velocity);
  r.seconds_correction = seconds_since(t0);
}

}  // namespace

int dense_image_grid_cells(long tets) {
  constexpr double kPointsPerTet = 2.2;
  const double cells = std::cbrt(6 * kPointsPerTet * static_cast<double>(std::max(tets, 0L)) / M_PI);
  return static_cast<int>(std::clamp(std::lround(cells), 24L, 128L));
}

DenseRegistrationResult register_dense(Device& dev, const DenseSubject& subject, const DenseTemplate& templ,
                                       const Points& landmarks, const Points& targets,
                                       const RegistrationOptions& lo, const DenseRegistrationOptions& o,
                                       const DenseImages* images) {
  Points& ball = subject.ball;
  const Tets& tets = subject.tets;
  const std::vector<int>& labels = subject.labels;
  const Points& tball = templ.ball;
  const Tets& ttets = templ.tets;
  const std::vector<int>& tlabels = templ.labels;
  const auto t_start = Clock::now();
  check_dense(tets, labels, ttets, tlabels, o);
  DenseRegistrationResult r;
  const DenseState st = dense_state(dev, ball, tets, labels, tball, ttets, tlabels, o, images);
  r.regions = st.regions;
  r.force = o.force;
  const Fit before(st, ball);
  r.agreement_before = before.agreement;
  r.mismatch_before = before.mismatch;
  Points work = ball;
  RegistrationOptions first = lo;
  first.restore_volumes = lo.restore_volumes && o.iterations == 0;
  auto t0 = Clock::now();
  r.landmark = register_landmarks(dev, work, tets, landmarks, targets, first);
  r.seconds_landmark = seconds_since(t0);
  r.max_normal_velocity = r.landmark.max_normal_velocity;
  Fit after_landmarks(st, work);
  r.agreement_landmarks = r.agreement_after = after_landmarks.agreement;
  r.mismatch_landmarks = r.mismatch_after = after_landmarks.mismatch;
  Points lm = r.landmark.landmarks_final;
  if (o.iterations > 0) {
    t0 = Clock::now();
    Points x(work.rows() + lm.rows(), 3);
    x << work, lm;
    Fit fit = std::move(after_landmarks);
    std::optional<Level> finest = dense_iterations(dev, st, x, o, fit, r);
    if (o.restore_cycles > 0 && lo.restore_volumes) {
      if (!finest) finest.emplace(o.widths.back(), o);
      const int n = std::max(1, o.iterations / static_cast<int>(o.widths.size()));
      const std::vector<char> pinned = landmark_vertices(ball, landmarks);
      for (int c = 0; c < o.restore_cycles && !r.time_budget_spent; ++c) {
        Points now = x.topRows(work.rows());
        restore_volumes(dev, {ball, tets, st.topology}, now, pinned, x.bottomRows(lm.rows()), restore_holds(st, now, o),
                        lo);
        x.topRows(work.rows()) = now;
        fit = Fit(st, now);
        level_iterations(dev, st, x, *finest, n, o, fit, r);
      }
      r.agreement_after = fit.agreement;
      r.mismatch_after = fit.mismatch;
    }
    finest.reset();  // its Gram matrix is large (about 230 MB at width 0.1)
    work = x.topRows(work.rows());
    lm = x.bottomRows(lm.rows());
    r.seconds_dense = seconds_since(t0);
    if (o.exact_landmarks) correct_landmarks(dev, work, tets, lm, targets, lo, r);
    if (o.refine.iterations > 0) {
      t0 = Clock::now();
      r.refine = refine_image(st, templ, *images, ball, work, lm, o.refine);
      r.seconds_refine = seconds_since(t0);
    }
    if (lo.restore_volumes) {
      t0 = Clock::now();
      r.restore = restore_volumes(dev, {ball, tets, st.topology}, work, landmark_vertices(ball, landmarks), lm,
                                  restore_holds(st, work, o), lo);
      r.seconds_restore = seconds_since(t0);
    }
  }
  finish(dev, r, st, work, lm, targets, lo.refuse_folds);
  ball = std::move(work);
  r.seconds_total = seconds_since(t_start);
  return r;
}

}  // namespace vpm
