// ---- dense registration: region boundaries, closest-point matches, smoothing, agreement ----
#include "register/dense_force.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_set>

#include "core/parallel.hpp"
#include "register/point_bins.hpp"
#include "vpm/labels.hpp"

namespace vpm {

std::vector<int> without_labels(const std::vector<int>& labels, const std::vector<int>& exclude) {
  const std::unordered_set<int> ex(exclude.begin(), exclude.end());
  std::vector<int> out(labels);
  for (int& l : out)
    if (l < 0 || ex.count(l)) l = 0;
  return out;
}

RegionFaces region_faces(const Tets& tets, const std::vector<int>& labels) {
  static const int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  struct Entry {
    std::array<int, 3> key;
    int tet;
  };
  std::vector<Entry> all;
  all.reserve(static_cast<size_t>(4 * tets.rows()));
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (const auto& f : kFace) {
      std::array<int, 3> k = {tets(t, f[0]), tets(t, f[1]), tets(t, f[2])};
      std::sort(k.begin(), k.end());
      all.push_back({k, static_cast<int>(t)});
    }
  std::sort(all.begin(), all.end(), [](const Entry& a, const Entry& b) { return a.key < b.key; });
  std::vector<std::pair<int, std::array<int, 3>>> out;  // (label, face)
  for (size_t i = 0; i < all.size();) {
    const bool pair = i + 1 < all.size() && all[i + 1].key == all[i].key;
    const int la = labels[static_cast<size_t>(all[i].tet)];
    const int lb = pair ? labels[static_cast<size_t>(all[i + 1].tet)] : 0;
    if (la != lb) {
      if (la > 0) out.push_back({la, all[i].key});
      if (lb > 0) out.push_back({lb, all[i].key});
    }
    i += pair ? 2 : 1;
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  RegionFaces rf;
  rf.faces.resize(static_cast<Eigen::Index>(out.size()), 3);
  for (size_t f = 0; f < out.size(); ++f) {
    rf.label.push_back(out[f].first);
    for (int c = 0; c < 3; ++c) rf.faces(static_cast<Eigen::Index>(f), c) = out[f].second[static_cast<size_t>(c)];
  }
  return rf;
}

RegionSurface region_surface(const Points& v, const RegionFaces& rf) {
  RegionSurface s;
  const Eigen::Index nf = rf.faces.rows();
  s.centroid.resize(nf, 3);
  s.area.resize(nf);
  for (Eigen::Index f = 0; f < nf; ++f) {
    const Eigen::Vector3d a = v.row(rf.faces(f, 0)), b = v.row(rf.faces(f, 1)), c = v.row(rf.faces(f, 2));
    s.centroid.row(f) = ((a + b + c) / 3).transpose();
    s.area(f) = 0.5 * (b - a).cross(c - a).norm();
    if (f == 0 || rf.label[static_cast<size_t>(f)] != rf.label[static_cast<size_t>(f - 1)]) {
      s.labels.push_back(rf.label[static_cast<size_t>(f)]);
      s.offset.push_back(static_cast<long>(f));
    }
  }
  s.offset.push_back(static_cast<long>(nf));
  return s;
}

namespace {

/// Rows [b, e) of `pts` sorted by x, for exact closest-point queries that scan outwards from
/// the query's x and stop where the x gap alone exceeds the best distance: the same answer as
/// a scan of all rows (the lowest row among equally close ones), in about sqrt(n) steps.
class SortedByX {
 public:
  SortedByX(const Points& pts, long b, long e) : pts_(pts) {
    for (long j = b; j < e; ++j) rows_.push_back(j);
    std::sort(rows_.begin(), rows_.end(), [&](long i, long j) { return pts(i, 0) < pts(j, 0) || (pts(i, 0) == pts(j, 0) && i < j); });
    for (long j : rows_) x_.push_back(pts(j, 0));
  }

  /// The row closest to `p` (the lowest of equally close rows); -1 when there are none.
  long closest(const Eigen::Vector3d& p) const {
    long best = -1;
    double d = std::numeric_limits<double>::infinity();
    auto consider = [&](size_t k) {  // false once the x gap alone is farther than the best
      const double gap = x_[k] - p(0);
      if (gap * gap > d) return false;
      const long j = rows_[k];
      const double dj = (pts_.row(j).transpose() - p).squaredNorm();  // >= gap^2: sums of squares round up from it
      if (dj < d || (dj == d && j < best)) {
        d = dj;
        best = j;
      }
      return true;
    };
    const size_t mid = static_cast<size_t>(std::lower_bound(x_.begin(), x_.end(), p(0)) - x_.begin());
    for (size_t k = mid; k < x_.size() && consider(k); ++k) {
    }
    for (size_t k = mid; k-- > 0 && consider(k);) {
    }
    return best;
  }

 private:
  const Points& pts_;
  std::vector<long> rows_;
  std::vector<double> x_;
};

/// One closest-point query of closest_matches: the point `at` of one side and the other
/// side's region it is matched against.
struct MatchQuery {
  long at;
  bool from_subject;
  size_t region;  ///< index into the region pairs
};

}  // namespace

BoundaryMatches closest_matches(const RegionSurface& s, const RegionSurface& t) {
  BoundaryMatches m;
  std::vector<SortedByX> sub, tem;  // per matched region: the subject's and the template's faces
  std::vector<MatchQuery> queries;
  for (size_t rs = 0; rs < s.labels.size(); ++rs) {
    const auto it = std::lower_bound(t.labels.begin(), t.labels.end(), s.labels[rs]);
    if (it == t.labels.end() || *it != s.labels[rs]) continue;
    const size_t rt = static_cast<size_t>(it - t.labels.begin());
    m.regions.push_back(s.labels[rs]);
    const long sb = s.offset[rs], se = s.offset[rs + 1], tb = t.offset[rt], te = t.offset[rt + 1];
    const size_t r = sub.size();
    sub.emplace_back(s.centroid, sb, se);
    tem.emplace_back(t.centroid, tb, te);
    for (long i = sb; i < se; ++i) queries.push_back({i, true, r});
    for (long j = tb; j < te; ++j) queries.push_back({j, false, r});
  }
  const Eigen::Index k = static_cast<Eigen::Index>(queries.size());
  m.at.resize(k, 3);
  m.displacement.resize(k, 3);
  m.weight.resize(k);
  detail::parallel_for(static_cast<int>(k), 256, [&](int q0, int q1) {
    for (int q = q0; q < q1; ++q) {
      const MatchQuery& mq = queries[static_cast<size_t>(q)];
      if (mq.from_subject) {  // a subject face to the closest template face of its region
        const Eigen::Vector3d p = s.centroid.row(mq.at).transpose();
        m.at.row(q) = p.transpose();
        m.displacement.row(q) = t.centroid.row(tem[mq.region].closest(p)) - p.transpose();
        m.weight(q) = s.area(mq.at);
      } else {  // a template face from the closest subject face of its region
        const Eigen::Vector3d p = t.centroid.row(mq.at).transpose();
        const Eigen::Vector3d from = s.centroid.row(sub[mq.region].closest(p)).transpose();
        m.at.row(q) = from.transpose();
        m.displacement.row(q) = (p - from).transpose();
        m.weight(q) = t.area(mq.at);
      }
    }
  });
  double wsum = 0, dsum = 0;
  for (Eigen::Index i = 0; i < k; ++i) {
    wsum += m.weight(i);
    dsum += m.weight(i) * m.displacement.row(i).norm();
  }
  const double mean_w = k > 0 && wsum > 0 ? wsum / static_cast<double>(k) : 1.0;
  m.weight /= mean_w;
  m.mean_distance = wsum > 0 ? dsum / wsum : 0.0;
  return m;
}

Points ball_grid(double h) {
  const int n = static_cast<int>(std::floor(1 / h));
  std::vector<Eigen::Vector3d> pts;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -n; k <= n; ++k) {
        const Eigen::Vector3d p(i * h, j * h, k * h);
        if (p.norm() < 1) pts.push_back(p);
      }
  Points out(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  return out;
}

Points smooth_matches(const BoundaryMatches& m, const Points& centres, double sigma, Eigen::VectorXd* mass) {
  Points out = Points::Zero(centres.rows(), 3);
  if (mass) mass->resize(centres.rows());
  const double cut = 3 * sigma, cut2 = cut * cut, inv = 1 / (sigma * sigma);
  const PointBins bins(m.at, cut);
  detail::parallel_for(static_cast<int>(centres.rows()), 64, [&](int c0, int c1) {
    for (int c = c0; c < c1; ++c) {
      const Eigen::Vector3d x = centres.row(c).transpose();
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      double wsum = 0;
      bins.visit(x, [&](int i) {
        const double d2 = (m.at.row(i).transpose() - x).squaredNorm();
        if (d2 > cut2) return;
        const double g = m.weight(i) * std::exp(-d2 * inv);
        sum += g * m.displacement.row(i).transpose();
        wsum += g;
      });
      out.row(c) = (sum / (wsum + 1)).transpose();
      if (mass) (*mass)(c) = wsum / (wsum + 1);
    }
  });
  return out;
}

double mean_dice(const std::vector<int>& a, const std::vector<int>& b, const std::vector<int>& regions) {
  if (regions.empty()) return 0;
  double sum = 0;
  for (const LabelOverlap& o : dice_overlap(a, b, regions)) sum += o.dice;
  return sum / static_cast<double>(regions.size());
}

}  // namespace vpm
