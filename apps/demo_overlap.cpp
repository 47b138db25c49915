// The demo's overlap measure (demo_overlap.hpp).
#include "demo_overlap.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "vpm/collective.hpp"
#include "vpm/locate.hpp"

namespace vpm::cli {

std::vector<int> carried_labels(const TetMesh& tm, const TetMesh& sm, const Points& subject_ball,
                                const Image& tmpl_atlas, const Image& subj_atlas, std::vector<size_t>& voxels) {
  const Points native = native_positions(sm, "demo: the subject's ball map");
  // the subject atlas's voxels inside the bounding box of the subject's mesh
  const Eigen::Vector3d lo = native.colwise().minCoeff().transpose(), hi = native.colwise().maxCoeff().transpose();
  std::array<int, 3> first{0, 0, 0}, last{-1, -1, -1};
  for (int c = 0; c < 8; ++c) {  // the box's corners in voxel indices
    const Eigen::Vector3d corner((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
    const Eigen::Vector3d v = subj_atlas.to_voxel(corner);
    for (int a = 0; a < 3; ++a) {
      const int f = std::max(0, static_cast<int>(std::floor(v[a]))), l = std::min(subj_atlas.dims[a] - 1, static_cast<int>(std::ceil(v[a])));
      first[a] = c == 0 ? f : std::min(first[a], f);
      last[a] = c == 0 ? l : std::max(last[a], l);
    }
  }
  std::vector<size_t> box;
  for (int k = first[2]; k <= last[2]; ++k)
    for (int j = first[1]; j <= last[1]; ++j)
      for (int i = first[0]; i <= last[0]; ++i) box.push_back(subj_atlas.index(i, j, k));
  Points world(static_cast<Eigen::Index>(box.size()), 3);
  for (size_t n = 0; n < box.size(); ++n) {
    const size_t i = box[n] % static_cast<size_t>(subj_atlas.dims[0]);
    const size_t j = (box[n] / static_cast<size_t>(subj_atlas.dims[0])) % static_cast<size_t>(subj_atlas.dims[1]);
    const size_t k = box[n] / (static_cast<size_t>(subj_atlas.dims[0]) * static_cast<size_t>(subj_atlas.dims[1]));
    world.row(static_cast<Eigen::Index>(n)) = subj_atlas.to_world(Eigen::Vector3d(double(i), double(j), double(k))).transpose();
  }
  // inside the subject's mesh: carried to its ball position, then into Colin27's native space
  const std::vector<Location> where = TetLocator(native, sm.tets).locate_all(world);
  voxels.clear();
  std::vector<Eigen::RowVector3d> ball;
  for (size_t n = 0; n < box.size(); ++n) {
    const Location& l = where[n];
    if (l.tet < 0 || !l.inside()) continue;
    Eigen::RowVector3d b = Eigen::RowVector3d::Zero();
    for (int c = 0; c < 4; ++c) b += l.bary[c] * subject_ball.row(sm.tets(l.tet, c));
    voxels.push_back(box[n]);
    ball.push_back(b);
  }
  Points ball_points(static_cast<Eigen::Index>(ball.size()), 3);
  for (size_t n = 0; n < ball.size(); ++n) ball_points.row(static_cast<Eigen::Index>(n)) = ball[n];
  const Points y = pull_back_points(ball_points, tm.vertices, tm.tets, native_positions(tm, "demo: colin27's ball map"));
  std::vector<int> out(ball.size());
  for (Eigen::Index n = 0; n < y.rows(); ++n)
    out[static_cast<size_t>(n)] =
        static_cast<int>(std::lround(sample_image(tmpl_atlas, y.row(n).transpose(), Interpolation::nearest)));
  return out;
}

std::vector<LabelOverlap> subject_space_dice(const TetMesh& tm, const TetMesh& sm, const Points& subject_ball,
                                             const Image& tmpl_atlas, const Image& subj_atlas,
                                             const std::vector<int>& evaluated, long& voxel_count) {
  std::vector<size_t> voxels;
  const std::vector<int> carried = carried_labels(tm, sm, subject_ball, tmpl_atlas, subj_atlas, voxels);
  std::vector<int> own(voxels.size());
  for (size_t i = 0; i < voxels.size(); ++i) own[i] = static_cast<int>(std::lround(subj_atlas.data[voxels[i]]));
  voxel_count = static_cast<long>(voxels.size());
  return dice_overlap(own, carried, evaluated);
}

}  // namespace vpm::cli
