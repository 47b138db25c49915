#include "vpm/locate.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "mesh/tet_grid.hpp"
#include "core/parallel.hpp"
#include "vpm/error.hpp"

namespace vpm {

struct TetLocator::Impl {
  Points x;
  Tets tets;
  std::vector<int> nbr;
  detail::TetGrid background;
  Impl(const Points& vertices, const Tets& t, std::vector<int> neighbours)
      : x(vertices), tets(t), nbr(std::move(neighbours)) {
    detail::build_background(background, x, tets, nbr);
  }
};

TetLocator::TetLocator(const Points& vertices, const Tets& tets)
    : impl_(std::make_unique<Impl>(vertices, tets, detail::tet_neighbors(tets))) {}

TetLocator::TetLocator(const Points& vertices, const Tets& tets, const TetTopology& topology) {
  if (topology.neighbours.size() != 4 * static_cast<size_t>(tets.rows()))
    throw InputError("TetLocator: the topology has " + std::to_string(topology.neighbours.size() / 4) + " tets, the mesh " +
                     std::to_string(tets.rows()));
  impl_ = std::make_unique<Impl>(vertices, tets, topology.neighbours);
}
TetLocator::~TetLocator() = default;
TetLocator::TetLocator(TetLocator&&) noexcept = default;
TetLocator& TetLocator::operator=(TetLocator&&) noexcept = default;

Location TetLocator::locate(const Eigen::Vector3d& p, int hint) const {
  Location out;
  const detail::TetGrid& f = impl_->background;
  if (f.m == 0) return out;
  if (hint < 0 || hint >= f.m) hint = detail::start_tet(f, p);  // a tet of p's grid cell when it has one
  long long st[3] = {0, 0, 0};
  out.tet = detail::locate(f, p, hint, out.bary, st);
  double raw[4];
  detail::bary(f, out.tet, p, raw);
  out.min_bary = *std::min_element(raw, raw + 4);
  return out;
}

const Tets& TetLocator::tets() const { return impl_->tets; }
const Points& TetLocator::vertices() const { return impl_->x; }

std::vector<Location> TetLocator::locate_all(const Points& points) const {
  const int k = static_cast<int>(points.rows());
  std::vector<Location> out(k);
  detail::parallel_for(k, 4096, [&](int begin, int end) {
    int hint = -1;
    for (int i = begin; i < end; ++i) {
      out[i] = locate(points.row(i).transpose(), hint);
      hint = out[i].tet;
    }
  });
  return out;
}

Points pull_back_points(const Points& s, const Points& ball, const Tets& tets, const Points& native) {
  if (ball.rows() != native.rows())
    throw InputError("pull_back: the ball mesh has " + std::to_string(ball.rows()) +
                     " vertices but its native positions " + std::to_string(native.rows()));
  return pull_back_points(s, TetLocator(ball, tets), native);
}

Points pull_back_points(const Points& s, const TetLocator& from, const Points& native) {
  const Tets& tets = from.tets();
  if (tets.size() > 0 && tets.maxCoeff() >= native.rows())
    throw InputError("pull_back: the mesh's tets use vertex " + std::to_string(tets.maxCoeff()) + " but its native positions " +
                     std::to_string(native.rows()));
  const std::vector<Location> loc = from.locate_all(s);
  Points out(s.rows(), 3);
  detail::parallel_for(static_cast<int>(s.rows()), 4096, [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      Eigen::RowVector3d p = Eigen::RowVector3d::Zero();
      for (int k = 0; k < 4; ++k) p += loc[i].bary[k] * native.row(tets(loc[i].tet, k));
      out.row(i) = p;
    }
  });
  return out;
}

}  // namespace vpm
