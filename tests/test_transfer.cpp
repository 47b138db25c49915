// Fields and registrations carried between two meshes of the same solid (vpm/transfer.hpp).
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "support/shapes.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"
#include "vpm/transfer.hpp"

using namespace vpm;

namespace {

// A smooth field on the ball with curvature in every component.
Eigen::MatrixXd smooth_field(const Points& x) {
  Eigen::MatrixXd f(x.rows(), 3);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    f.row(i) << std::sin(2 * x(i, 0)), std::cos(3 * x(i, 1)), x(i, 0) * x(i, 2);
  return f;
}

double max_row_distance(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).rowwise().norm().maxCoeff();
}

// The ball twisted about z by 0.6 r^2 radians: smooth, one to one, the sphere onto itself.
Points twist(const Points& x) {
  Points y(x.rows(), 3);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const Eigen::Vector3d p = x.row(i).transpose();
    y.row(i) = (Eigen::AngleAxisd(0.6 * p.squaredNorm(), Eigen::Vector3d::UnitZ()) * p).transpose();
  }
  return y;
}

// `ball` with its native space: the ball scaled to a 60 mm brain-sized solid somewhere else.
TetMesh with_native(TetMesh ball) {
  FieldValues native = (60.0 * ball.vertices).rowwise() + Eigen::RowVector3d(10, -20, 5);
  ball.set_point_field("original_position", native);
  return ball;
}

int inverted(const Points& x, const Tets& tets) {
  const Eigen::VectorXd v = tet_volumes(x, tets);
  return static_cast<int>((v.array() <= 0).count());
}

}  // namespace

TEST_CASE("carry_vertex_field: linear fields exactly, smooth ones to second order, coarse -> fine -> coarse within interpolation error") {
  const TetMesh coarse = test::smooth_ball_mesh(6), fine = test::smooth_ball_mesh(12), finer = test::smooth_ball_mesh(24);
  const TetLocator at_coarse(coarse.vertices, coarse.tets), at_fine(fine.vertices, fine.tets);

  // a linear field: exact wherever the point lies inside the coarse mesh
  Eigen::Matrix3d a;
  a << 1, 2, -1, 0.5, -3, 2, 4, 0, 1;
  const Eigen::MatrixXd lin_c = (coarse.vertices * a.transpose()).rowwise() + Eigen::RowVector3d(1, -2, 3);
  const Eigen::MatrixXd lin_f = (fine.vertices * a.transpose()).rowwise() + Eigen::RowVector3d(1, -2, 3);
  const Eigen::MatrixXd carried_lin = carry_vertex_field(at_coarse, lin_c, fine.vertices);
  const std::vector<Location> loc = at_coarse.locate_all(fine.vertices);
  int inside = 0;
  for (Eigen::Index i = 0; i < fine.vertices.rows(); ++i)
    if (loc[static_cast<size_t>(i)].inside()) {
      ++inside;
      CHECK((carried_lin.row(i) - lin_f.row(i)).norm() < 1e-11);
    }
  CHECK(inside > fine.vertices.rows() / 2);

  // a smooth field: one way, then back
  const Eigen::MatrixXd f_c = smooth_field(coarse.vertices), f_f = smooth_field(fine.vertices);
  const Eigen::MatrixXd to_fine = carry_vertex_field(at_coarse, f_c, fine.vertices);
  const double one_way = max_row_distance(to_fine, f_f);
  const Eigen::MatrixXd back = carry_vertex_field(at_fine, to_fine, coarse.vertices);
  const double round_trip = max_row_distance(back, f_c);
  CHECK(one_way > 0);
  CHECK(one_way < 0.15);  // h^2 / 8 x the largest second derivative (9): 0.125 at spacing 1/3
  CHECK(round_trip <= 2 * one_way);
  // halving the coarse mesh's spacing divides the error by about 4 (second order): from the fine
  // mesh to a finer one
  const Eigen::MatrixXd from_fine = carry_vertex_field(at_fine, f_f, finer.vertices);
  const double finer_way = max_row_distance(from_fine, smooth_field(finer.vertices));
  CHECK(finer_way < 0.4 * one_way);

  // a field too short for the mesh
  CHECK_THROWS_AS(carry_vertex_field(at_coarse, f_c.topRows(10), fine.vertices), InputError);
}

TEST_CASE("carry_registration: a coarse mesh's map to the ball carried onto a fine mesh and back") {
  TetMesh coarse = with_native(test::smooth_ball_mesh(6));
  TetMesh fine = with_native(test::smooth_ball_mesh(14));
  const Points coarse_unit = coarse.vertices, fine_unit = fine.vertices;
  coarse.vertices = twist(coarse_unit);  // the coarse mesh registered by a smooth map

  const CarriedRegistration carried = carry_registration(coarse, fine);
  CHECK(carried.folded == 0);  // a smooth map onto a finer mesh: nothing to untangle
  CHECK(carried.inverted == 0);
  const Points& on_fine = carried.ball;
  REQUIRE(on_fine.rows() == fine.num_vertices());
  const double one_way = max_row_distance(on_fine, twist(fine_unit));
  CHECK(one_way < 0.08);
  CHECK(inverted(on_fine, fine.tets) == 0);
  const std::vector<char> boundary = boundary_vertex_mask(fine.num_vertices(), boundary_faces(fine.tets));
  for (Eigen::Index v = 0; v < on_fine.rows(); ++v)
    if (boundary[static_cast<size_t>(v)]) CHECK(std::abs(on_fine.row(v).norm() - 1) < 1e-12);

  // and back onto the coarse mesh: within the interpolation error of where it started
  fine.vertices = on_fine;
  TetMesh coarse_again = coarse;
  const Points back = carry_registration(fine, coarse_again).ball;
  CHECK(max_row_distance(back, coarse.vertices) <= 2 * one_way);
  CHECK(inverted(back, coarse.tets) == 0);

  // the identity carried is (nearly) the target's own positions in the ball
  TetMesh id = with_native(test::smooth_ball_mesh(6));
  CHECK(max_row_distance(carry_registration(id, fine).ball, fine_unit) < 0.05);

  // a map that bends within a coarse tet folds some of the fine tets carried through it: those
  // are untangled, boundary on the sphere
  TetMesh bent = with_native(test::smooth_ball_mesh(4));
  for (Eigen::Index i = 0; i < bent.vertices.rows(); ++i) {
    const Eigen::Vector3d p = bent.vertices.row(i).transpose();
    bent.vertices.row(i) = (Eigen::AngleAxisd(2.5 * p.squaredNorm(), Eigen::Vector3d::UnitZ()) * p).transpose();
  }
  const CarriedRegistration untangled = carry_registration(bent, fine);
  CHECK(untangled.folded > 0);
  CHECK(untangled.inverted == 0);
  CHECK(inverted(untangled.ball, fine.tets) == 0);

  TetMesh bare = test::smooth_ball_mesh(6);
  CHECK_THROWS_AS(carry_registration(bare, fine), InputError);
  CHECK_THROWS_AS(carry_registration(coarse, bare), InputError);
}
