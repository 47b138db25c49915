// Step 4 of the initial map: untangling the harmonic map (map/initial_untangle.hpp).
#include "map/initial_untangle.hpp"

#include <algorithm>
#include <vector>

#include "vpm/device.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"
#include "vpm/untangle.hpp"

namespace vpm::detail {

namespace {

// The last resort for a few folds the fixed boundary leaves (seen on the feet of a humanoid
// model: a tet on the boundary whose chord triangle left no room for its fourth vertex): the
// boundary vertices of the folded tets may move too, then go back onto the sphere along their
// radius, flipped sphere triangles are unflipped along the sphere and the tets untangled with
// the boundary fixed; kept when it leaves fewer folds and flips no boundary triangle, up to 3
// times. Fills rep.untangle_slide; returns the folds left.
int slide_cleanup(Device& device, const TetMesh& m, const std::vector<char>& boundary, const InitialMapOptions& opt,
                  Points& ball, int folds, InitialMapReport& rep) {
  const int n = m.num_vertices();
  const Triangles bfaces = boundary_faces(m.tets);
  const int rings = 2 * opt.local_untangle_rings;
  for (int attempt = 0; attempt < 3 && folds > 0; ++attempt) {
    const std::vector<int> bad = inverted_tets(ball, m.tets);
    std::vector<char> fixed = boundary, slid(static_cast<size_t>(n), 0);
    for (int t : bad)
      for (int c = 0; c < 4; ++c) {
        const auto v = static_cast<size_t>(m.tets(t, c));
        slid[v] = boundary[v];
        fixed[v] = 0;
      }
    Points trial = ball;
    const UntangleResult r = untangle_local(device, m.vertices, m.tets, trial, fixed, bad, rings, opt.untangle_options);
    for (int v = 0; v < n; ++v)
      if (slid[static_cast<size_t>(v)]) trial.row(v).normalize();
    // the projection can flip boundary triangles and fold tets: unflip along the sphere (the
    // previous state as the shape to keep), then untangle with the boundary fixed again
    unflip_sphere_faces(ball, bfaces, trial, {});
    const std::vector<int> again = inverted_tets(trial, m.tets);
    if (!again.empty())
      untangle_local(device, m.vertices, m.tets, trial, boundary, again, rings, opt.untangle_options);
    const int left = static_cast<int>(inverted_tets(trial, m.tets).size());
    rep.untangle_slide = InitialUntangle{r, true, rings};
    rep.untangle_slide->result.inverted_after = left;
    if (left >= folds || flipped_sphere_triangles(trial, bfaces) > 0) break;
    ball = std::move(trial);
    folds = left;
  }
  return folds;
}

}  // namespace

// The options with every untangling run capped by what is left of opt.deadline.
static InitialMapOptions within_budget(const InitialMapOptions& opt) {
  InitialMapOptions o = opt;
  if (opt.deadline.set()) {
    const double left = std::max(opt.deadline.remaining(), 1e-6);
    double& cap = o.untangle_options.max_seconds;
    cap = cap > 0 ? std::min(cap, left) : left;
  }
  return o;
}

// Local runs widen the rings this many times (x2 each) while each leaves fewer folds.
constexpr int kLocalWidenings = 3;
int untangle_map(Device& device, const TetMesh& m, const std::vector<char>& boundary, const InitialMapOptions& options,
                 Points& ball, InitialMapReport& rep, bool global, bool local_tried) {
  int folds = rep.folds_before_untangle;
  const InitialMapOptions opt = within_budget(options);
  const bool run = opt.untangle == InitialMapOptions::Untangle::Always ||
                   (opt.untangle == InitialMapOptions::Untangle::IfFolded && folds > 0);
  if (!run) return folds;
  const bool local = opt.untangle == InitialMapOptions::Untangle::IfFolded && opt.local_untangle_rings > 0;
  if (local && !(local_tried && rep.untangle)) {  // few folds: free only their neighbourhood, widening it while that helps
    Points trial = ball;
    int left = folds;
    UntangleOptions lo = opt.untangle_options;
    lo.stalled_sigma_min = opt.local_untangle_sigma_min;
    for (int k = 0, rings = opt.local_untangle_rings; k < kLocalWidenings && left > 0; ++k, rings *= 2) {
      const UntangleResult ul = untangle_local(device, m.vertices, m.tets, trial, boundary,
                                               inverted_tets(trial, m.tets), rings, lo);
      rep.untangle = InitialUntangle{ul, true, rings};
      if (ul.inverted_after >= left) break;  // no progress: the global run takes over
      left = ul.inverted_after;
    }
    folds = left;
    if (folds == 0 || !global) ball = std::move(trial);  // without the global run: the fewest folds
  }
  if (!local || (folds > 0 && global)) {  // Always (or no rings): the global run is what was asked
    UntangleOptions whole = opt.untangle_options;
    whole.max_outer_iterations = std::max(whole.max_outer_iterations, opt.global_untangle_max_outer_iterations);
    whole.max_lbfgs_iterations = std::max(whole.max_lbfgs_iterations, opt.global_untangle_max_lbfgs_iterations);
    const UntangleResult ur = untangle(device, m.vertices, m.tets, ball, boundary, whole);
    if (local) rep.untangle_local_failed = rep.untangle;
    rep.untangle = InitialUntangle{ur, false, 0};
    folds = ur.inverted_after;
    if (folds > 0 && folds <= kCleanupMaxFolds && opt.local_untangle_rings > 0) {
      // a few folds left by the global run: free a wider neighbourhood of each (the global
      // run's small theta keeps shape, the local one's reference is the input there)
      const int rings = 2 * opt.local_untangle_rings;
      Points trial = ball;
      const UntangleResult uc = untangle_local(device, m.vertices, m.tets, trial, boundary,
                                               inverted_tets(ball, m.tets), rings, opt.untangle_options);
      rep.untangle_cleanup = InitialUntangle{uc, true, rings};
      if (uc.inverted_after < folds) {
        ball = std::move(trial);
        folds = uc.inverted_after;
      }
    }
  }
  if (folds > 0 && folds <= kCleanupMaxFolds) folds = slide_cleanup(device, m, boundary, opt, ball, folds, rep);
  return folds;
}

bool refine_folds(Device& device, const Triangles& bf, const InitialMapOptions& opt, InitialMapResult& res,
                  InitialMapReport& rep) {
  int folds = rep.folds_after_untangle;
  if (folds == 0 || opt.max_refine_rounds <= 0 || opt.untangle == InitialMapOptions::Untangle::Never) return false;
  const auto t0 = Clock::now();
  InitialMapReport::Refine rf;
  rf.folds_before = folds;
  const std::string kBall = "vpm_refine_ball";  // the ball positions, carried to the midpoints
  for (int round = 0, rings = 1; round < opt.max_refine_rounds && folds > 0 && !opt.deadline.passed();
       ++round, rings *= 2) {
    TetMesh carrier = res.mesh;
    carrier.set_point_field(kBall, FieldValues(res.ball));
    SplitResult sp = split_edges_near(carrier, bf, inverted_tets(res.ball, carrier.tets), rings);
    TetMesh& m = sp.mesh;
    Points ball = m.find_point_field(kBall)->values;
    m.point_data.erase(std::find_if(m.point_data.begin(), m.point_data.end(),
                                    [&](const Field& f) { return f.name == kBall; }));
    std::vector<char> boundary = res.boundary;
    boundary.resize(static_cast<size_t>(m.num_vertices()), 0);  // inserted vertices are interior
    InitialMapReport sub;
    sub.folds_before_untangle = static_cast<int>(inverted_tets(ball, m.tets).size());
    const int left = untangle_map(device, m, boundary, opt, ball, sub);
    ++rf.rounds;
    if (left >= folds) break;  // no better: the mesh before this round stays
    folds = left;
    res.mesh = std::move(m);
    res.ball = std::move(ball);
    res.boundary = std::move(boundary);
    rf.inserted_vertices += sp.inserted_vertices;
    rep.untangle = sub.untangle;
  }
  rf.folds_after = folds;
  rf.seconds = seconds_since(t0);
  rep.refine = rf;
  rep.folds_after_untangle = folds;
  rep.refined_vertices = res.mesh.num_vertices();
  rep.refined_tets = res.mesh.num_tets();
  return rf.inserted_vertices > 0;
}

}  // namespace vpm::detail
