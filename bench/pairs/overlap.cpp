// The benchmark's overlap measures (overlap.hpp).
#include "pairs/overlap.hpp"

#include <algorithm>
#include <cmath>

#include "apps/demo_overlap.hpp"
#include "vpm/collective.hpp"
#include "vpm/locate.hpp"
#include "vpm/timing.hpp"

namespace vpm::bench {

namespace {

// Labels of ball `points` read from a subject's atlas image through its ball mesh at `ball`.
std::vector<int> image_labels(const Points& points, const Points& ball, const TetMesh& mesh,
                              const Image& atlas) {
  const Points x = pull_back_points(points, ball, mesh.tets, native_positions(mesh, "demo: the ball map"));
  std::vector<int> out(static_cast<size_t>(x.rows()));
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    out[static_cast<size_t>(i)] =
        static_cast<int>(std::lround(sample_image(atlas, x.row(i).transpose(), Interpolation::nearest)));
  return out;
}

double mean_dice(const std::vector<LabelOverlap>& v) {
  double s = 0;
  for (const auto& o : v) s += o.dice;
  return v.empty() ? 0.0 : s / v.size();
}

}  // namespace

Overlap measure_overlap(const TetMesh& tm, const TetMesh& sm, const Points& registered,
                        const std::vector<int>& lab_t, const std::vector<int>& lab_s,
                        const std::vector<int>& labels, const std::vector<int>& evaluated, int grid,
                        const Image& tmpl_atlas, const Image& subj_atlas) {
  const auto t0 = Clock::now();
  const Points samples = ball_grid_points(grid);
  const std::vector<int> s_t = sample_labels(tm.vertices, tm.tets, lab_t, samples);
  const std::vector<int> s_before = sample_labels(sm.vertices, sm.tets, lab_s, samples);
  const std::vector<int> s_after = sample_labels(registered, sm.tets, lab_s, samples);
  Overlap o;
  o.points = static_cast<long>(samples.rows());
  o.before = dice_overlap(s_t, s_before, evaluated);
  o.after = dice_overlap(s_t, s_after, evaluated);
  o.landmark_before = mean_dice(dice_overlap(s_t, s_before, labels));
  o.landmark_after = mean_dice(dice_overlap(s_t, s_after, labels));
  const std::vector<int> i_t = image_labels(samples, tm.vertices, tm, tmpl_atlas);
  const std::vector<int> i_before = image_labels(samples, sm.vertices, sm, subj_atlas);
  const std::vector<int> i_after = image_labels(samples, registered, sm, subj_atlas);
  o.image_before = dice_overlap(i_t, i_before, evaluated);
  o.image_after = dice_overlap(i_t, i_after, evaluated);
  o.image_landmark_before = mean_dice(dice_overlap(i_t, i_before, labels));
  o.image_landmark_after = mean_dice(dice_overlap(i_t, i_after, labels));
  o.subject_before = cli::subject_space_dice(tm, sm, sm.vertices, tmpl_atlas, subj_atlas, evaluated, o.subject_voxels);
  o.subject_after = cli::subject_space_dice(tm, sm, registered, tmpl_atlas, subj_atlas, evaluated, o.subject_voxels);
  o.seconds = seconds_since(t0);
  return o;
}

double volume_bound(const LabelOverlap& o) {
  const long long s = o.count_a + o.count_b;
  return s > 0 ? 2.0 * static_cast<double>(std::min(o.count_a, o.count_b)) / static_cast<double>(s) : 1.0;
}

}  // namespace vpm::bench
