#include <catch2/catch.hpp>
#include <cmath>

#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"
#include "vpm/volume_map.hpp"

using namespace vpm;

namespace {
// A smooth fold-free warp of the ball that keeps the sphere in place: radial power law plus
// a bump that shifts the centre along x (det J >= 0.7 for the bump).
Points warp(const Points& x, double power = 1.6, double shift = 0.15) {
  Points y = x;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    Eigen::Vector3d p = x.row(i).transpose();
    const double r = p.norm();
    if (r > 0) p *= std::pow(r, power - 1.0);
    p.x() += shift * (1.0 - p.squaredNorm());
    y.row(i) = p.transpose();
  }
  return y;
}

double max_boundary_radius_error(const Points& x, const Tets& t) {
  const auto mask = boundary_vertex_mask(static_cast<int>(x.rows()), boundary_faces(t));
  double e = 0;
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    if (mask[i]) e = std::max(e, std::fabs(x.row(i).norm() - 1.0));
  return e;
}
}  // namespace

TEST_CASE("a Moser round lowers the distortion, keeps the boundary on the sphere, folds nothing") {
  const TetMesh m = test::ball_mesh(6);
  const Points start = warp(m.vertices);
  const DistortionPair d0 = volume_distortion(m.vertices, start, m.tets);
  REQUIRE(d0.folds == 0);
  REQUIRE(d0.vertex > 0.2);
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    Points ball = start;
    VolumeMapOptions o;
    o.rounds = 1;
    const VolumeMapResult r = volume_preserving_map(*dev, m.vertices, m.tets, ball, o);
    REQUIRE(r.rounds.size() == 1);
    const DistortionPair d1 = volume_distortion(m.vertices, ball, m.tets);
    CHECK(d1.folds == 0);
    CHECK(d1.vertex < 0.5 * d0.vertex);
    CHECK(d1.tet < d0.tet);
    CHECK(r.final_vertex_mean_abs_dev == Approx(d1.vertex));
    CHECK(max_boundary_radius_error(ball, m.tets) < 1e-12);
    // boundary vertices moved (slide), i.e. the boundary is not frozen
    CHECK((ball - start).rowwise().norm().maxCoeff() > 1e-3);
  }
}
